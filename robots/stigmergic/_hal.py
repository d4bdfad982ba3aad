"""The hardware of the two kinds of robot (Ducatelle et al., section 2), as the robot sees it.

An eye-bot hangs from the ceiling: a clock, a downward camera that shows the foot-bots below as
their LEDs (the top beacon, the front LED when it is on, both in the eye-bot's own frame, whose x
axis is its reference direction θ0, shown to the foot-bots by its red front and blue back LEDs),
and its infrared range-and-bearing (IrRB) transmitter, a cone that reaches only the foot-bots
under it: hand it the instruction, it sends that from the next tick on.

A foot-bot drives on the ground: a clock, the differential drive and its odometry, a ring of
proximity sensors, its LEDs (one status string: :func:`robots.stigmergic.show_leds`), the
upward camera and IrRB receiver (the eye-bot above: who, where its θ0 points in the foot-bot's
frame, and the last instruction it sent; None under none), the omnidirectional camera (eye-bots
in range as distance and bearing) and the area sensor (a floor colour, say: in the source, in
the target, or neither).

Protocols, satisfied structurally by the simulated hardware (``sim_hw.continuous``, the
``eyebot`` and ``footbot`` backends) and, one day, by real robots; nothing here imports
``sim_hw``, and nothing here is ground truth (the radio's locator excepted, which only the
transport's range-limited broadcast uses). Both bundles have what the robot process touches on
any hardware (``robots.backend.BaseHardware``): the clock's idling, a drive to stop, the radio.
Also here: the ``robot.*`` procedures each kind exports, and the two readings both the robot
processes and the in-process runner turn into the behaviours' perceptions
(:func:`footbot_seen`, :func:`obstacle_bearing`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from robots.hal import Clock, Drive, Led, Odometry, RadioLocator, Sonar
from robots.library._geometry import Point

from ._eyebot import FootBotSeen, Goal, Instruction
from ._footbot import Heard
from ._leds import read as read_leds

__all__ = [
    "AreaSensor",
    "DownCamera",
    "EyeBotHardware",
    "FootBotHardware",
    "Hanging",
    "IrRB",
    "OmniCamera",
    "Spot",
    "UpCamera",
    "eyebot_procedures",
    "footbot_procedures",
    "footbot_seen",
    "obstacle_bearing",
]


@dataclass(frozen=True, slots=True)
class Spot:
    """One foot-bot as the downward camera sees it: its top beacon and its front LED (None:
    off), metres in the eye-bot's frame (x along θ0), and its LED status string."""

    beacon: Point
    front: Point | None
    led: str


@runtime_checkable
class DownCamera(Protocol):
    """The eye-bot's downward camera: a disc of radius ``view`` on the ground below it."""

    view: float

    def below(self) -> tuple[Spot, ...]:
        """The foot-bots in view at the last tick."""
        ...


@runtime_checkable
class IrRB(Protocol):
    """The eye-bot's infrared range-and-bearing transmitter: a cone of radius ``cone`` on the
    ground, which only the foot-bots under it hear."""

    cone: float

    def send(self, instruction: Instruction) -> None:
        """Broadcast ``instruction`` (θ_s, θ_t relative to θ0) from the next tick on, until
        another one is sent."""
        ...


@runtime_checkable
class Hanging(Protocol):
    """An eye-bot attached to the ceiling has nothing to drive: ``stop`` (which the robot
    process calls when the robot becomes idle) keeps it where it is."""

    def stop(self) -> None:
        """Stay attached."""
        ...


@runtime_checkable
class UpCamera(Protocol):
    """The foot-bot's upward camera and IrRB receiver."""

    def above(self) -> Heard | None:
        """The eye-bot whose broadcast reached it at the last tick — its id, its θ0 as the
        camera reads its LEDs (radians in the foot-bot's frame) and the instruction it sent —
        or None (under no eye-bot, or under one that has sent nothing yet)."""
        ...


@runtime_checkable
class OmniCamera(Protocol):
    """The foot-bot's omnidirectional camera: eye-bots within ``max_range`` (horizontally)."""

    max_range: float

    def eyebots(self) -> tuple[tuple[float, float], ...]:
        """(distance m, bearing rad) of the eye-bots in range, nearest first."""
        ...


@runtime_checkable
class AreaSensor(Protocol):
    """The foot-bot's sensor of the source and target areas (a floor colour)."""

    def area(self) -> Goal | None:
        """The area it is in (Goal.SOURCE or Goal.TARGET), or None."""
        ...


@dataclass(frozen=True, slots=True)
class EyeBotHardware:
    """Everything an eye-bot's process can touch."""

    id: str
    clock: Clock
    camera: DownCamera
    irrb: IrRB
    drive: Hanging
    radio: RadioLocator | None = None


@dataclass(frozen=True, slots=True)
class FootBotHardware:
    """Everything a foot-bot's process can touch."""

    id: str
    clock: Clock
    drive: Drive
    odometry: Odometry
    sonar: Sonar
    led: Led
    up: UpCamera
    omni: OmniCamera
    area: AreaSensor
    radio: RadioLocator | None = None


# -- readings into perceptions (shared with experiments/eyebot/_trial.py) ------------------------


def footbot_seen(beacon: Point, front: Point | None, led: str, weight: float = 1.0) -> FootBotSeen:
    """A foot-bot in view as the eye-bot's behaviour takes it: its LED status read for the
    beacon's colour (avoiding) and the front LED's (its goal); a status that is not a
    foot-bot's counts as plain with the front LED off."""
    shown = read_leds(led)
    avoiding, goal = shown if shown is not None else (False, None)
    return FootBotSeen(beacon, avoiding, front, goal, weight)


def obstacle_bearing(
    ranges: Sequence[float], angles: Sequence[float], avoid: float
) -> float | None:
    """The bearing of the nearest obstacle within ±π/2 of the heading if it is closer than
    ``avoid`` metres to the rim (the proximity ring's ``ranges`` along ``angles``), else None."""
    ahead = [
        (r, bearing)
        for r, angle in zip(ranges, angles, strict=True)
        if abs(bearing := math.remainder(angle, 2.0 * math.pi)) < math.pi / 2
    ]
    near = min(ahead, default=None)
    return near[1] if near is not None and near[0] < avoid else None


# -- the robot.* procedures ---------------------------------------------------------------------


def eyebot_procedures(hw: EyeBotHardware) -> dict[str, Callable[..., Any]]:
    """``robot.pose`` (an eye-bot's own frame: always the origin), ``robot.stop`` and
    ``robot.sense`` (``time`` and ``below``: ``[beacon, front, led]`` per foot-bot in view)."""

    def sense() -> dict[str, Any]:
        """What the eye-bot sees now."""
        return {
            "time": hw.clock.now(),
            "below": [
                [list(s.beacon), list(s.front) if s.front else None, s.led]
                for s in hw.camera.below()
            ],
        }

    def pose() -> list[float]:
        """An eye-bot's pose in its own frame (it does not move): [0, 0, 0]."""
        return [0.0, 0.0, 0.0]

    def stop() -> None:
        """Nothing to stop: it hangs still."""
        hw.drive.stop()

    return {"robot.pose": pose, "robot.stop": stop, "robot.sense": sense}


def footbot_procedures(hw: FootBotHardware) -> dict[str, Callable[..., Any]]:
    """``robot.pose``, ``robot.stop`` and ``robot.sense`` (``time``, ``pose``, ``sonar``,
    ``above``: ``[eye-bot, θ0, θ_s, θ_t]`` or None, ``eyebots``: ``[distance, bearing]`` each,
    ``area``: ``"source"``, ``"target"`` or None)."""

    def sense() -> dict[str, Any]:
        """What the foot-bot senses now."""
        heard = hw.up.above()
        area = hw.area.area()
        return {
            "time": hw.clock.now(),
            "pose": list(hw.odometry.pose()),
            "sonar": list(hw.sonar.ranges()),
            "above": None
            if heard is None
            else [heard.eyebot, heard.reference, heard.to_source, heard.to_target],
            "eyebots": [list(e) for e in hw.omni.eyebots()],
            "area": None if area is None else area.value,
        }

    def pose() -> list[float]:
        """The foot-bot's dead-reckoned pose (x, y, heading)."""
        return list(hw.odometry.pose())

    def stop() -> None:
        """Stop the motors."""
        hw.drive.stop()

    return {"robot.pose": pose, "robot.stop": stop, "robot.sense": sense}
