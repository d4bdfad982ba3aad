"""The hardware backends of the continuous world process, over zenoh.

``sim`` (``mover robot --hardware sim``): a body in the world; it joins the world process named
by the ``world`` option (default ``"world"``) through :func:`~sim_hw.continuous._hardware.remote`,
and offers the robot process the procedures of a robot with a body
(:func:`robots.procedures.body_procedures`).

``eyebot`` and ``footbot``: the two kinds of Ducatelle et al.'s heterogeneous swarm in a world
whose file hangs eye-bots from the ceiling (``_skyworld``): each gets the HAL of its kind
(``robots.stigmergic``: :class:`EyeBotHardware`, :class:`FootBotHardware`) and exports that
kind's ``robot.*`` procedures. A backend per kind, as ``sim`` and ``grid`` are, because the two
have different hardware types: the process is handed exactly its kind's devices, and the world
refuses a join of the wrong kind at once.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from robots.hal import Hardware
from robots.procedures import body_procedures
from robots.stigmergic import (
    EyeBotHardware,
    FootBotHardware,
    eyebot_procedures,
    footbot_procedures,
)

from ._contract import EYEBOT, FOOTBOT
from ._hardware import remote
from ._kinds import join_remote

if TYPE_CHECKING:
    from mover import Node
    from robots.backend import HardwareBackend


K = TypeVar("K", bound=EyeBotHardware | FootBotHardware)

OPTIONS = frozenset({"world", "call_timeout"})
"""What every backend here takes: which world to join, and how long a call to it may take."""


def _link(options: Mapping[str, Any]) -> dict[str, Any]:
    """The link to the world from a backend's options: ``world`` (default ``"world"``) and
    ``call_timeout`` (seconds, default 30)."""
    return {
        "world": str(options.get("world", "world")),
        "call_timeout": float(options.get("call_timeout", 30.0)),
    }


class ContinuousBackend:
    """Joins a continuous world process; a :class:`robots.backend.HardwareBackend`."""

    options = OPTIONS

    async def connect(
        self, node: Node, robot_id: str, spec: Mapping[str, Any], **options: Any
    ) -> Hardware:
        """Join the world ``world`` (default ``"world"``) as ``robot_id`` with body ``spec``.

        ``call_timeout`` (seconds, default 30): a call to the world not answered in that time
        is asked again while the world is alive.
        """
        return await remote(
            node,
            robot_id,
            dict(spec) or None,
            **_link(options),
        )

    def procedures(self, hw: Hardware) -> Mapping[str, Callable[..., Any]]:
        """``robot.pose``, ``robot.stop``, ``robot.sense`` of a robot with a body."""
        return body_procedures(hw)


BACKEND: HardwareBackend[Hardware] = ContinuousBackend()


class KindBackend(Generic[K]):
    """Joins a continuous world process with a ceiling as one of its ``kind`` (an eye-bot or a
    foot-bot, whose hardware is a ``hardware``); a ``HardwareBackend``."""

    options = OPTIONS

    def __init__(
        self,
        kind: str,
        hardware: type[K],
        procedures: Callable[[K], Mapping[str, Callable[..., Any]]],
    ) -> None:
        self.kind = kind
        self.hardware: type[K] = hardware
        self._procedures: Callable[[K], Mapping[str, Callable[..., Any]]] = procedures

    async def connect(
        self, node: Node, robot_id: str, spec: Mapping[str, Any], **options: Any
    ) -> K:
        """Join the world ``world`` (default ``"world"``) as ``robot_id`` of this kind: an
        eye-bot is one of its file's ``[[eyebots]]`` (``spec`` must be empty), a foot-bot has
        body ``spec`` (over the world file's). ``call_timeout`` as for ``sim``."""
        hw = await join_remote(node, robot_id, self.kind, spec, **_link(options))
        assert isinstance(hw, self.hardware)
        return hw

    def procedures(self, hw: K) -> Mapping[str, Callable[..., Any]]:
        """``robot.pose``, ``robot.stop``, ``robot.sense`` of a robot of this kind."""
        return self._procedures(hw)


EYEBOT_BACKEND: HardwareBackend[EyeBotHardware] = KindBackend(
    EYEBOT, EyeBotHardware, eyebot_procedures
)
FOOTBOT_BACKEND: HardwareBackend[FootBotHardware] = KindBackend(
    FOOTBOT, FootBotHardware, footbot_procedures
)
