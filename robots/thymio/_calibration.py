"""A Thymio II's calibration: motor units to metres per second, wheel base, the proximity curve.

Pure numbers and functions, no I/O. The defaults are those measured in Aseba Playground
(Debian's aseba 1.6.99, Enki physics) by ``python -m robots.thymio.calibrate``, which prints
them afresh; docs/thymio.md says how they were measured and what a physical robot is
known to differ by. Every figure can be given per robot in its spec (``spec.calibration``).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any

__all__ = ["PROX_ANGLES", "Calibration"]

PROX_ANGLES: tuple[float, ...] = (0.69, 0.30, 0.0, -0.30, -0.69, math.pi, math.pi)
"""Direction of ``prox.horizontal[0..6]`` from the heading (left positive): five at the front
from left to right, two at the back (left, right), as on the robot's body."""

#: Raw ``prox.horizontal`` reading → distance in metres from the sensor, measured in the
#: Playground by ``python -m robots.thymio.calibrate`` (robots facing a wall at known
#: distances; the sensor sits 0.080 m ahead of the wheels' axis): the reading falls as the
#: wall goes away. Below the first point the sensor counts as seeing nothing.
PLAYGROUND_PROX: tuple[tuple[int, float], ...] = (
    (1511, 0.120),
    (1691, 0.110),
    (1897, 0.100),
    (2130, 0.090),
    (2394, 0.080),
    (2689, 0.070),
    (3011, 0.060),
    (3348, 0.050),
    (3688, 0.040),
    (4005, 0.030),
    (4266, 0.020),
    (4367, 0.015),
    (4442, 0.010),
    (4489, 0.005),
    (4504, 0.000),
)


@dataclass(frozen=True, slots=True)
class Calibration:
    """How raw Thymio readings and commands map to SI units.

    ``speed_per_unit``: m/s of one ``motor.*.target`` / ``motor.*.speed`` unit;
    ``wheel_base``: metres between the wheels' contact points; ``max_target``: the largest
    motor target (the firmware's ±500); ``prox``: (raw, metres) points of the proximity curve,
    raw increasing (interpolated linearly; a reading under the first point sees nothing);
    ``white``: the ground sensors' ``prox.ground.delta`` on a white floor (reflectance 1).
    """

    speed_per_unit: float = 3.26e-4
    wheel_base: float = 0.094
    max_target: int = 500
    prox: tuple[tuple[int, float], ...] = field(default=PLAYGROUND_PROX)
    white: float = 1000.0

    @classmethod
    def of(cls, spec: Mapping[str, Any]) -> Calibration:
        """The defaults with what ``spec`` (a robot spec's ``calibration`` table) overrides;
        ValueError naming an unknown key or a bad value."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(spec) - known)
        if unknown:
            raise ValueError(
                f"calibration: no key {', '.join(unknown)} (known: {', '.join(sorted(known))})"
            )
        cal = replace(cls(), **{k: v for k, v in spec.items() if k != "prox"})
        if "prox" in spec:
            cal = replace(cal, prox=tuple((int(r), float(m)) for r, m in spec["prox"]))
        cal.check()
        return cal

    def check(self) -> None:
        """ValueError unless the figures make sense (positive, the curve monotonic)."""
        if not (self.speed_per_unit > 0 and self.wheel_base > 0 and self.max_target > 0):
            raise ValueError("calibration: speed_per_unit, wheel_base, max_target must be > 0")
        raws = [r for r, _ in self.prox]
        metres = [m for _, m in self.prox]
        if len(raws) < 2 or raws != sorted(raws) or metres != sorted(metres, reverse=True):
            raise ValueError(
                "calibration: prox needs 2 or more (raw, metres) points, raw increasing and "
                "metres decreasing"
            )

    @property
    def max_speed(self) -> float:
        """The fastest wheel speed, in m/s."""
        return self.max_target * self.speed_per_unit

    @property
    def reach(self) -> float:
        """The proximity sensors' reach in metres (what a sensor that sees nothing reads)."""
        return self.prox[0][1]

    def targets(self, v: float, omega: float) -> tuple[int, int]:
        """Motor targets (left, right) for ``v`` m/s and ``omega`` rad/s; a command beyond a
        wheel's reach is scaled down whole (the turn radius kept)."""
        half = omega * self.wheel_base / 2
        left, right = (v - half) / self.speed_per_unit, (v + half) / self.speed_per_unit
        over = max(abs(left), abs(right)) / self.max_target
        if over > 1:
            left, right = left / over, right / over
        return round(left), round(right)

    def motion(self, left: float, right: float) -> tuple[float, float]:
        """(v m/s, omega rad/s) of measured wheel speeds ``left``, ``right`` in motor units."""
        vl, vr = left * self.speed_per_unit, right * self.speed_per_unit
        return (vl + vr) / 2, (vr - vl) / self.wheel_base

    def distance(self, raw: int) -> float:
        """Metres from the sensor for a raw proximity reading (:attr:`reach`: nothing seen)."""
        return interpolate(self.prox, raw)

    def reflectance(self, raw: int) -> float:
        """A ground reading as reflectance, 0 (black) to 1 (white)."""
        return min(max(raw / self.white, 0.0), 1.0)


def interpolate(points: Sequence[tuple[int, float]], raw: int) -> float:
    """Piecewise-linear ``points`` (raw increasing) at ``raw``, held at the ends."""
    raws = [r for r, _ in points]
    i = bisect.bisect_right(raws, raw)
    if i == 0:
        return points[0][1]
    if i == len(points):
        return points[-1][1]
    (r0, m0), (r1, m1) = points[i - 1], points[i]
    return m0 + (m1 - m0) * (raw - r0) / (r1 - r0)
