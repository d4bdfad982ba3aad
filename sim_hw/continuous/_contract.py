"""What a robot and the continuous world exchange each tick: the command and the readings.

One definition for both ends: the world builds :class:`Readings` in ``World._measure`` and
applies :class:`Command` in ``World.set_command``; the robot-side backend (``_hardware``) builds
the command and reads the readings. Over zenoh they travel as msgpack maps with these keys.
"""

from __future__ import annotations

from typing import Any, TypedDict

from robots.hal import BumperSide

DT = 1.0 / 60.0
"""Seconds of one physics step."""
STEPS_PER_TICK = 6
"""Physics steps in one control tick."""
TICK = DT * STEPS_PER_TICK
"""Seconds of one control tick (a robot's command and readings)."""
EYEBOT, FOOTBOT = "eyebot", "footbot"
"""The two kinds a join's settings may name (``{"kind": ...}``)."""


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


# -- the ceiling (worlds with eye-bots: ``sim_hw.continuous._skyworld``) ----------------------


class EyeCommand(TypedDict, total=False):
    """An eye-bot's command for the next tick; a missing key keeps its last value."""

    irrb: list[float]
    """``[θ_s, θ_t]`` (radians relative to θ0): what its IrRB cone sends from now on."""


class EyeReadings(TypedDict):
    """What an eye-bot measured at the end of a tick."""

    tick: int
    """Ticks done."""
    t: float
    """Simulated seconds."""
    below: list[list[Any]]
    """The downward camera: ``[bx, by, fx, fy, led]`` per foot-bot in view, its beacon (b) and
    front LED (f; None, None when off) in the eye-bot's frame (m, x along θ0)."""


class FootReadings(Readings):
    """A foot-bot's readings: a ground robot's, and the devices that look up."""

    above: list[Any] | None
    """``[eye-bot, θ0, θ_s, θ_t]``: the eye-bot whose cone it is in, θ0 as its upward camera
    reads it (radians in the foot-bot's frame) and the instruction last sent; None under no
    eye-bot (or one that has sent nothing yet)."""
    omni: list[list[float]]
    """``[distance, bearing]`` of each eye-bot the omnidirectional camera sees, nearest first."""
    area: str | None
    """The id of the area the robot is in (``source``, ``target``), or None."""
