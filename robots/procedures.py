"""The ``robot.*`` procedures a robot process exports, one set per kind of hardware.

``robot.pose``, ``robot.stop`` and ``robot.sense`` let a teammate or a tool (``mover call``) ask
a robot where it thinks it is, stop it, and see what it senses. What there is to sense depends
on the hardware, so each set is written for one hardware type and a backend
(``robots.backend``) says which set its hardware offers; nothing here asks a device whether it
exists beyond what the type says may be absent. Results are plain data (lists, dicts, numbers,
strings), as they cross the wire.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from typing import Any, Protocol

from .grid_hal import GridHardware
from .hal import Hardware

__all__ = ["body_procedures", "grid_procedures"]


def body_procedures(hw: Hardware) -> dict[str, Callable[..., Any]]:
    """``robot.pose``, ``robot.stop`` and ``robot.sense`` of a robot with a body.

    ``robot.sense`` gives ``time``, ``pose`` and, for each optional device, its reading or None
    when the robot has no such device: ``sonar`` (ranges), ``bumper`` (the side pressed),
    ``camera`` (``[kind, id, status, range, bearing]`` per sighting).
    """

    def sense() -> dict[str, Any]:
        """What the robot senses now."""
        return {
            "time": hw.clock.now(),
            "pose": list(hw.odometry.pose()),
            "sonar": list(hw.sonar.ranges()) if hw.sonar is not None else None,
            "bumper": hw.bumper.side() if hw.bumper is not None else None,
            "camera": [[s.kind, s.id, s.status, s.range, s.bearing] for s in hw.camera.sightings()]
            if hw.camera is not None
            else None,
        }

    return {**_pose_and_stop(hw.odometry, hw.drive), "robot.sense": sense}


def grid_procedures(hw: GridHardware) -> dict[str, Callable[..., Any]]:
    """``robot.pose``, ``robot.stop`` and ``robot.sense`` of a robot on a grid.

    ``robot.pose`` is the cells moved from the start, ``[d_row, d_col, 0.0]``; ``robot.sense``
    gives ``round``, ``pose``, ``here`` (the cell under the robot) and ``around`` (the
    neighbouring cells in direction order), each cell a dict of the fields of
    :class:`~robots.grid_hal.Here` / :class:`~robots.grid_hal.Near`.
    """

    def sense() -> dict[str, Any]:
        """What the robot perceives this round."""
        return {
            "round": hw.clock.now(),
            "pose": list(hw.odometry.pose()),
            "here": asdict(hw.senses.here()),
            "around": [asdict(near) for near in hw.senses.around()],
        }

    return {**_pose_and_stop(hw.odometry, hw.drive), "robot.sense": sense}


class _Odometry(Protocol):
    def pose(self) -> tuple[float, float, float]: ...


class _Stoppable(Protocol):
    def stop(self) -> None: ...


def _pose_and_stop(odometry: _Odometry, drive: _Stoppable) -> dict[str, Callable[..., Any]]:
    def pose() -> list[float]:
        """The robot's dead-reckoned pose (x, y, heading; on a grid: d_row, d_col, 0)."""
        return list(odometry.pose())

    def stop() -> None:
        """Stop the motors (on a grid: stay this round)."""
        drive.stop()

    return {"robot.pose": pose, "robot.stop": stop}
