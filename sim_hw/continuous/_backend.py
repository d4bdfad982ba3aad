"""The ``sim`` hardware backend: a body in the continuous world process, over zenoh.

Installed as the ``mover.hardware`` entry point ``sim`` (``mover robot --hardware sim``): it
joins the world process named by the ``world`` option (default ``"world"``) through
:func:`~sim_hw.continuous._hardware.remote`, and offers the robot process the procedures of a
robot with a body (:func:`robots.procedures.body_procedures`).
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


class ContinuousBackend:
    """Joins a continuous world process; a :class:`robots.backend.HardwareBackend`."""

    options = frozenset({"world", "call_timeout"})

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
            world=str(options.get("world", "world")),
            call_timeout=float(options.get("call_timeout", 30.0)),
        )

    def procedures(self, hw: Hardware) -> Mapping[str, Callable[..., Any]]:
        """``robot.pose``, ``robot.stop``, ``robot.sense`` of a robot with a body."""
        return body_procedures(hw)


BACKEND: HardwareBackend[Hardware] = ContinuousBackend()
