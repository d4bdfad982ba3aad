"""Small plane geometry shared by the library procedures (poses are (x, y, heading))."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

Point = tuple[float, float]
Pose = tuple[float, float, float]

Region = Callable[[Point], bool]
"""A predicate on positions (x, y in the odometry frame): where a procedure may go or find.

Any function of a point will do (``lambda p: p[0] > 0``); :class:`Rect` is one that also knows
its centre, so a walk started outside it can find its way in.
"""


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangle, usable as a :data:`Region`: ``Rect(0, 0, 4, 4)((1, 2))``.

    :meth:`split` cuts it into a grid, e.g. the four quadrants of an arena for four robots.
    """

    x_min: float
    y_min: float
    x_max: float
    y_max: float

    def __call__(self, point: Sequence[float]) -> bool:
        """Whether ``point`` (a point or a pose) lies inside, edges included."""
        return self.x_min <= point[0] <= self.x_max and self.y_min <= point[1] <= self.y_max

    @property
    def centre(self) -> Point:
        """The rectangle's centre."""
        return ((self.x_min + self.x_max) / 2.0, (self.y_min + self.y_max) / 2.0)

    def split(self, columns: int = 2, rows: int = 2) -> list[Rect]:
        """The rectangle cut into ``columns`` × ``rows`` equal cells, row by row from
        (x_min, y_min): ``split()`` gives the quadrants south-west, south-east, north-west,
        north-east."""
        w = (self.x_max - self.x_min) / columns
        h = (self.y_max - self.y_min) / rows
        return [
            Rect(
                self.x_min + i * w,
                self.y_min + j * h,
                self.x_min + (i + 1) * w,
                self.y_min + (j + 1) * h,
            )
            for j in range(rows)
            for i in range(columns)
        ]


def wrap(angle: float) -> float:
    """``angle`` folded into (-π, π]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi


def ahead(pose: Pose, distance: float, bearing: float = 0.0) -> Point:
    """The point ``distance`` away from ``pose`` at ``bearing`` from its heading."""
    x, y, th = pose
    return (x + distance * math.cos(th + bearing), y + distance * math.sin(th + bearing))


def to_frame(origin: Pose, local: Point) -> Point:
    """A point given in the frame of ``origin`` (x along its heading), in the outer frame."""
    x, y, th = origin
    c, s = math.cos(th), math.sin(th)
    return (x + c * local[0] - s * local[1], y + s * local[0] + c * local[1])


def from_frame(origin: Pose, point: Point) -> Point:
    """A point of the outer frame, in the frame of ``origin``."""
    x, y, th = origin
    dx, dy = point[0] - x, point[1] - y
    c, s = math.cos(th), math.sin(th)
    return (c * dx + s * dy, -s * dx + c * dy)


def bearing_to(pose: Pose, point: Point) -> float:
    """Bearing of ``point`` from ``pose``'s heading, in (-π, π]."""
    return wrap(math.atan2(point[1] - pose[1], point[0] - pose[0]) - pose[2])


def distance(a: Sequence[float], b: Sequence[float]) -> float:
    """Euclidean distance between the (x, y) of two points or poses."""
    return math.hypot(a[0] - b[0], a[1] - b[1])


def clip(value: float, low: float, high: float) -> float:
    """``value`` limited to [low, high]."""
    return min(max(value, low), high)
