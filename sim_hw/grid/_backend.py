"""The ``grid`` hardware backend: a robot on the grid world process, over zenoh.

Installed as the ``mover.hardware`` entry point ``grid`` (``mover robot --hardware grid``): it
joins the grid world process named by the ``world`` option (default ``"gridworld"``) through
:func:`~sim_hw.grid._hardware.connect`, and offers the robot process the procedures of a robot
on a grid (:func:`robots.procedures.grid_procedures`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from robots.grid_hal import GridHardware
from robots.procedures import grid_procedures

from ._hardware import connect

if TYPE_CHECKING:
    from mover import Node
    from robots.backend import HardwareBackend


class GridBackend:
    """Joins a grid world process; a :class:`robots.backend.HardwareBackend`."""

    options = frozenset({"world", "call_timeout", "idle_period"})

    async def connect(
        self, node: Node, robot_id: str, spec: Mapping[str, Any], **options: Any
    ) -> GridHardware:
        """Join the grid world ``world`` (default ``"gridworld"``) as ``robot_id``.

        ``call_timeout`` (seconds, default 30): a call to the world not answered in that time
        is asked again while the world is alive; ``idle_period`` (seconds, default 0.01) paces
        the ticks of tasks that do not own the clock.
        """
        return await connect(
            node,
            robot_id,
            dict(spec),
            world=str(options.get("world", "gridworld")),
            call_timeout=float(options.get("call_timeout", 30.0)),
            idle_period=float(options.get("idle_period", 0.01)),
        )

    def procedures(self, hw: GridHardware) -> Mapping[str, Callable[..., Any]]:
        """``robot.pose``, ``robot.stop``, ``robot.sense`` of a robot on a grid."""
        return grid_procedures(hw)


BACKEND: HardwareBackend[GridHardware] = GridBackend()
