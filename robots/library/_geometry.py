"""Small plane geometry shared by the library procedures (poses are (x, y, heading))."""

from __future__ import annotations

import math
from collections.abc import Sequence

Point = tuple[float, float]
Pose = tuple[float, float, float]


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
