"""mover: program a team of mobile robots as one distributed program.

The public face of the middleware: a :class:`Node` per process (RPC, range-limited broadcasts,
liveliness, and ``node.membership``, the live view of who is in the team) that joins a team with
its :class:`TeamCredentials` (the team's name and key); programs (:class:`ProgramHost`,
:func:`launch`, and ``PROGRESS_TOPIC``, the topic under which members report a run's progress:
``f"{PROGRESS_TOPIC}/{run}"``), each run of which gets its :class:`RunTeam` (the members of the
run and the collectives ``distributed_or`` / ``distributed_and``, in simulated time over a
:class:`RunClock`); the errors (:class:`FileError` the base of every file's, in ``sim_hw`` too),
and :class:`ExpectedFault`, the mark of a fault that is reported in one line rather than as a
bug. Everything else lives in private modules; the command-line
helpers shared by every process are in :mod:`mover.cli`.

Deprecated (they warn, and go in the next release): ``Team`` (now :class:`TeamCredentials`),
``TaskTeam`` (now :class:`RunTeam`), and ``Collectives``, ``StepMetrics`` and ``free_port``
(internals: a program never needs them).
"""

import importlib as _importlib
import typing as _typing
from collections.abc import Callable as _Callable

from . import _deprecated
from ._clock import IdleClock
from ._collective import OperationFailed, Outcome, RunClock
from ._config import NodeConfig, TeamCredentials
from ._exceptions import (
    Answered,
    BadArguments,
    CallError,
    CallTimeout,
    ConfigError,
    ExpectedFault,
    FileError,
    MemberLost,
    MoverError,
    NameTaken,
    NodeClosed,
    NotDelivered,
    PayloadTooLarge,
    Refused,
    RemoteError,
    RobotLost,
    UnknownProcedure,
    UnknownRobot,
    Unreachable,
    WireError,
)
from ._membership import MemberEvent, MemberInfo, Membership
from ._node import Node
from ._programs import PROGRESS_TOPIC, ProgramHost, RunTeam, launch
from ._radio import FixedLocator, Locator, Message, Neighbour, RadioModel, Subscription
from ._rpc import procedure
from ._wire import pack, unpack

__all__ = [
    "PROGRESS_TOPIC",
    "Answered",
    "BadArguments",
    "CallError",
    "CallTimeout",
    "ConfigError",
    "ExpectedFault",
    "FileError",
    "FixedLocator",
    "IdleClock",
    "Locator",
    "MemberEvent",
    "MemberInfo",
    "MemberLost",
    "Membership",
    "Message",
    "MoverError",
    "NameTaken",
    "Neighbour",
    "Node",
    "NodeClosed",
    "NodeConfig",
    "NotDelivered",
    "OperationFailed",
    "Outcome",
    "PayloadTooLarge",
    "ProgramHost",
    "RadioModel",
    "Refused",
    "RemoteError",
    "RobotLost",
    "RunClock",
    "RunTeam",
    "Subscription",
    "TeamCredentials",
    "UnknownProcedure",
    "UnknownRobot",
    "Unreachable",
    "WireError",
    "launch",
    "pack",
    "procedure",
    "unpack",
]

if _typing.TYPE_CHECKING:  # the deprecated names (see __getattr__), typed as they were
    from ._collective import Collectives as Collectives
    from ._collective import StepMetrics as StepMetrics
    from ._collective import TaskTeam as TaskTeam
    from ._config import free_port as free_port

    Team = TeamCredentials


def _moved(module: str, name: str) -> _Callable[[], object]:
    def find() -> object:
        return getattr(_importlib.import_module(module, __name__), name)

    return find


# Deprecated names: (where each is now, the advice its warning gives); see mover._deprecated.
_DEPRECATED: dict[str, tuple[_Callable[[], object], str]] = {
    "Team": (_moved("._config", "TeamCredentials"), "use mover.TeamCredentials (the same class)"),
    "TaskTeam": (
        _moved("._collective", "TaskTeam"),
        "use mover.RunTeam (the same team, with report)",
    ),
    "Collectives": (_moved("._collective", "Collectives"), "an internal: ProgramHost makes one"),
    "StepMetrics": (
        _moved("._collective", "StepMetrics"),
        "an internal: RunTeam.metrics holds them",
    ),
    "free_port": (_moved("._config", "free_port"), "an internal: NodeConfig listens on port 0"),
}


def __getattr__(name: str) -> object:
    """The deprecated names, with a DeprecationWarning (PEP 562)."""
    if name not in _DEPRECATED:
        raise AttributeError(f"module 'mover' has no attribute {name!r}")
    find, advice = _DEPRECATED[name]
    _deprecated.warn(f"mover.{name}", advice)
    return find()
