"""A Thymio II's devices over the HAL (``robots.hal``), fed by its clock's readings.

Each device reads the readings of the last control tick (:class:`Readings`) and leaves its
commands for the next one, as the HAL's conventions ask; ``_clock`` moves both over the link.
The calibration (``_calibration``) turns raw units into metres, seconds and radians.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass

from robots.hal import Pose

from ._calibration import PROX_ANGLES, Calibration

__all__ = [
    "BUTTONS",
    "COLOURS",
    "Buttons",
    "Ground",
    "Leds",
    "Proximity",
    "Readings",
    "ThymioDrive",
    "ThymioOdometry",
]

BUTTONS = ("backward", "left", "center", "forward", "right")
"""The five capacitive buttons on top, in the order of the firmware's ``button.*``."""

#: Colours a status (``Led.show``) lights the top LED with, RGB 0..32 each.
COLOURS: dict[str, tuple[int, int, int]] = {
    "": (0, 0, 0),
    "off": (0, 0, 0),
    "red": (32, 0, 0),
    "green": (0, 32, 0),
    "blue": (0, 0, 32),
    "yellow": (32, 32, 0),
    "cyan": (0, 32, 32),
    "magenta": (32, 0, 32),
    "white": (32, 32, 32),
}


@dataclass(frozen=True, slots=True)
class Readings:
    """One tick's raw readings: ``t`` (seconds, the host's wall clock when they came),
    ``prox`` (7), ``ground`` (2, ``prox.ground.delta``), ``speeds`` (left, right measured),
    ``buttons`` (5, in :data:`BUTTONS` order), ``leds`` (11: the lights the robot's LED
    program last applied, :meth:`Leds.words`' order; empty: not read)."""

    t: float
    prox: tuple[int, ...]
    ground: tuple[int, int]
    speeds: tuple[int, int]
    buttons: tuple[int, ...]
    leds: tuple[int, ...] = ()


class _Fed:
    """A device that reads its clock's current readings (set by the clock each tick)."""

    def __init__(self, cal: Calibration, readings: Readings) -> None:
        self.cal = cal
        self.readings = readings


class ThymioDrive:
    """``robots.hal.Drive``: (v, omega) to the two motor targets, by the calibration."""

    def __init__(self, cal: Calibration) -> None:
        self.cal = cal
        self.max_speed = cal.max_speed
        self.targets = (0, 0)
        """The motor targets the next tick sends (left, right)."""

    def set_velocity(self, v: float, omega: float) -> None:
        """Drive at ``v`` m/s and ``omega`` rad/s from the next tick (clipped, turn kept)."""
        self.targets = self.cal.targets(v, omega)

    def stop(self) -> None:
        """Both targets 0 from the next tick."""
        self.targets = (0, 0)


class ThymioOdometry(_Fed):
    """``robots.hal.Odometry``: dead reckoning from the measured wheel speeds.

    Integrates ``motor.*.speed`` over the time between readings (midpoint rule), from the
    spawn pose given in the spec. It drifts: wheel slip, the speed readings' noise and the
    calibration's error all add up, with no correction.
    """

    def __init__(self, cal: Calibration, readings: Readings, start: Pose) -> None:
        super().__init__(cal, readings)
        self._pose = start

    def pose(self) -> Pose:
        """The dead-reckoned (x, y, heading)."""
        return self._pose

    def advance(self, new: Readings) -> None:
        """Integrate from the current readings to ``new`` (the clock calls it, then feeds)."""
        dt = new.t - self.readings.t
        if dt > 0:
            v, w = self.cal.motion(*new.speeds)
            x, y, th = self._pose
            mid = th + w * dt / 2
            self._pose = (x + v * dt * math.cos(mid), y + v * dt * math.sin(mid), th + w * dt)


class Proximity(_Fed):
    """``robots.hal.Sonar`` of the 7 horizontal infrared sensors, in metres from the sensor.

    Short reach (about 12 cm): a sensor that sees nothing reads ``max_range``. What the
    infrared sees depends on the obstacle's colour and material; the curve is a white wall's.
    """

    angles = PROX_ANGLES

    def __init__(self, cal: Calibration, readings: Readings) -> None:
        super().__init__(cal, readings)
        self.max_range = cal.reach

    def ranges(self) -> tuple[float, ...]:
        """Distance to the nearest obstacle per sensor (``max_range``: none seen)."""
        return tuple(self.cal.distance(raw) for raw in self.readings.prox)

    def raw(self) -> tuple[int, ...]:
        """The raw ``prox.horizontal`` values (0: nothing; about 4500: touching)."""
        return self.readings.prox


class Ground(_Fed):
    """The two ground sensors under the front: the floor's reflectance, 0 (black) to 1."""

    def reflectance(self) -> tuple[float, float]:
        """(left, right) reflectance of the floor under the sensors."""
        return (self.cal.reflectance(self.readings.ground[0]),
                self.cal.reflectance(self.readings.ground[1]))  # fmt: skip

    def dark(self, below: float = 0.5) -> bool:
        """Whether both sensors see a floor darker than ``below``."""
        return max(self.reflectance()) < below


class Buttons(_Fed):
    """The five buttons on top."""

    def pressed(self) -> frozenset[str]:
        """The names (:data:`BUTTONS`) of the buttons pressed at the last tick."""
        return frozenset(n for n, v in zip(BUTTONS, self.readings.buttons, strict=True) if v)


class Leds:
    """``robots.hal.Led`` and the Thymio's own lights: the top RGB LED and the ring of 8.

    ``show(status)`` lights the top LED with the status's colour: a name of
    :data:`COLOURS`, ``#rrggbb``, or any other text as a colour of its own (the same text,
    the same colour), since the Thymio has no display. Applied at the next tick.
    """

    def __init__(self) -> None:
        self.top_rgb = (0, 0, 0)
        self.circle_levels: tuple[int, ...] = (0,) * 8
        self.readings: Readings | None = None
        """The last tick's readings (set by the clock)."""

    def show(self, status: str) -> None:
        """Light the top LED with ``status``'s colour (see the class)."""
        self.top_rgb = colour_of(status)

    def top(self, r: int, g: int, b: int) -> None:
        """Set the top LED, each channel 0..32."""
        self.top_rgb = (_level(r), _level(g), _level(b))

    def circle(self, levels: tuple[int, ...]) -> None:
        """Set the ring of 8 LEDs (clockwise from the front), each 0..32."""
        if len(levels) != 8:
            raise ValueError(f"the circle has 8 LEDs, got {len(levels)} levels")
        self.circle_levels = tuple(_level(v) for v in levels)

    def words(self) -> tuple[int, ...]:
        """The 11 words the LED program reads: top r, g, b, then the circle."""
        return self.top_rgb + self.circle_levels

    def shown(self) -> tuple[tuple[int, int, int], tuple[int, ...]] | None:
        """What the robot's LED program last applied at the last tick: (top r, g, b), (the
        circle's 8); None before it ran. It runs 20 times a second on the robot, so a command
        shows here a tick or two after it was sent."""
        if self.readings is None or len(self.readings.leds) != 11:
            return None
        words = self.readings.leds
        return (words[0], words[1], words[2]), words[3:]


def _level(v: int) -> int:
    return min(max(int(v), 0), 32)


def colour_of(status: str) -> tuple[int, int, int]:
    """The top LED's colour for ``status`` (see :class:`Leds`)."""
    if status in COLOURS:
        return COLOURS[status]
    if len(status) == 7 and status[0] == "#":
        try:
            rgb = int(status[1:], 16)
        except ValueError:
            pass
        else:
            return (
                (rgb >> 16) * 32 // 255,
                ((rgb >> 8) & 255) * 32 // 255,
                (rgb & 255) * 32 // 255,
            )
    h = zlib.crc32(status.encode())
    return (8 + h % 25, 8 + (h >> 8) % 25, 8 + (h >> 16) % 25)
