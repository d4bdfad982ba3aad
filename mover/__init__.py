"""mover: program a team of mobile robots as one distributed program.

The public face of the middleware: a :class:`Node` per process (RPC, range-limited broadcasts,
liveliness and team membership over Eclipse Zenoh), the :class:`Team` and its key, the
collectives (:class:`TaskTeam` with ``distributed_or`` / ``distributed_and``, in simulated time
over a :class:`RunClock`), programs (:class:`ProgramHost`, :func:`launch`, and
``PROGRESS_TOPIC``, the topic under which members report a run's progress:
``f"{PROGRESS_TOPIC}/{run}"``) and the errors. Everything else lives in
private modules; the command-line helpers shared by every process are in :mod:`mover.cli`.
"""

from ._clock import IdleClock
from ._collective import Collectives, OperationFailed, Outcome, RunClock, StepMetrics, TaskTeam
from ._config import NodeConfig, Team, free_port
from ._exceptions import (
    Answered,
    BadArguments,
    CallError,
    CallTimeout,
    ConfigError,
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
    "Collectives",
    "ConfigError",
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
    "StepMetrics",
    "Subscription",
    "TaskTeam",
    "Team",
    "UnknownProcedure",
    "UnknownRobot",
    "WireError",
    "free_port",
    "launch",
    "pack",
    "procedure",
    "unpack",
]
