"""The hardware backends of the continuous world process, over zenoh.

``sim`` (``mover robot --hardware sim``): a body in the world; it joins the world process named
by the ``world`` option (default ``"world"``) through :func:`~sim_hw.continuous._hardware.remote`,
and offers the robot process the procedures of a robot with a body
(:func:`robots.procedures.body_procedures`). ``eyebot`` and ``footbot``, the kinds of a world
whose file hangs eye-bots from the ceiling (``_skyworld``), are in ``_kind_backends``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from robots.hal import Hardware
from robots.procedures import body_procedures

from ._hardware import remote

if TYPE_CHECKING:
    from mover import Node
    from robots.backend import HardwareBackend

OPTIONS = frozenset({"world", "call_timeout"})
"""What every backend here takes: which world to join, and how long a call to it may take."""


def link_options(options: Mapping[str, Any]) -> dict[str, Any]:
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
            **link_options(options),
        )

    def procedures(self, hw: Hardware) -> Mapping[str, Callable[..., Any]]:
        """``robot.pose``, ``robot.stop``, ``robot.sense`` of a robot with a body."""
        return body_procedures(hw)


BACKEND: HardwareBackend[Hardware] = ContinuousBackend()
