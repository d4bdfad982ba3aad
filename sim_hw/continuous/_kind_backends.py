"""The backends of the two kinds of a world with a ceiling: ``eyebot`` and ``footbot``.

Ducatelle et al.'s heterogeneous swarm: each kind gets the HAL of its kind
(``robots.stigmergic``: :class:`EyeBotHardware`, :class:`FootBotHardware`) and exports that
kind's ``robot.*`` procedures. A backend per kind, as ``sim`` and ``grid`` are, because the two
have different hardware types: the process is handed exactly its kind's devices, and the world
refuses a join of the wrong kind at once. Apart from ``sim``'s module (``_backend``) so that a
``sim`` robot does not load the stigmergic library (and numpy with it).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from robots.stigmergic import (
    EyeBotHardware,
    FootBotHardware,
    eyebot_procedures,
    footbot_procedures,
)

from ._backend import OPTIONS, link_options
from ._contract import EYEBOT, FOOTBOT
from ._kinds import join_remote

if TYPE_CHECKING:
    from mover import Node
    from robots.backend import HardwareBackend


K = TypeVar("K", bound=EyeBotHardware | FootBotHardware)


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
        hw = await join_remote(node, robot_id, self.kind, spec, **link_options(options))
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
