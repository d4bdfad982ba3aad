"""What a robot and the continuous world exchange each tick: the command and the readings.

One definition for both ends: the world builds :class:`Readings` in ``World._measure`` and
applies :class:`Command` in ``World.set_command``; the robot-side backend (``_hardware``) builds
the command and reads the readings. Over zenoh they travel as msgpack maps with these keys.
"""

from __future__ import annotations

from typing import Any, TypedDict

from robots.hal import BumperSide


class Command(TypedDict, total=False):
    """A robot's command for the next tick; a missing key keeps its last value."""

    v: float
    """Forward speed, m/s (clipped to the robot's ``max_speed``)."""
    w: float
    """Turn rate, rad/s (clipped to ``max_turn``)."""
    push: float | None
    """Push with at most this force (N), or None: not pushing."""
    led: str
    """The LED status others' cameras read."""
    floor: list[Any]
    """``[value, colour]`` written to the floor cell under the robot (applies once)."""


class Readings(TypedDict):
    """What a robot measured at the end of a tick."""

    tick: int
    """Ticks done."""
    t: float
    """Simulated seconds."""
    sonar: list[float] | None
    """Sonar ranges (m), one per ray, or None without a sonar."""
    bump: BumperSide | None
    """The side of the bumper that touches (``front``, ``left``, ``right``, ``back``)."""
    odom: list[float]
    """Dead-reckoned ``[x, y, heading]``."""
    cam: list[list[Any]] | None
    """Camera sightings ``[kind, id, status, range, bearing]``, or None without a camera."""
    loc: list[float] | None
    """Ground truth ``[x, y, heading]`` for the radio locator, or None without a radio."""
    floor: list[Any]
    """``[value, colour]`` of the floor cell under the robot."""
    push: list[Any] | None
    """``[object id or None, displacement m]`` of the push under way, or None."""
