"""Pusher/steerer manipulation (Jennings et al., sections 4.1 "Manipulation" and 4.3, after
Brown and Jennings [BJ95]): move an object along a path given relative to where it is, the
object pinned between robots at its rear face.

As measured in docs/physics.md, the pusher stands at one rear corner and holds a constant
speed (0.3 m/s); the steerer stands at the other and adjusts its speed by up to ±0.2 m/s to
turn the object back onto the path; either alone only pivots it. Neither talks to the other:
each keeps the object where its camera first saw it (so it stays square to the face), and the
steerer reads the object's pose from that sighting and its own odometry. With more robots the
extra ones are steerers spread along the face (one in the middle has no lever arm and simply
pushes).

Decision rules: :class:`Path` (progress and errors along a polyline), :func:`stations`
(who stands where), :func:`object_pose`, :func:`pusher_command`, :func:`steerer_command`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from robots._robot import Robot
from robots.hal import Sighting

from ._geometry import Point, Pose, clip, wrap


@dataclass(frozen=True)
class Path:
    """A polyline starting at ``origin``; ``points`` are offsets from ``origin`` (same axes).

    Section 4.1: "our robots currently move the object relative to its current position".
    """

    origin: Point
    points: tuple[Point, ...]

    @classmethod
    def relative(cls, origin: Sequence[float], offsets: Sequence[Sequence[float]]) -> Path:
        """The path through ``origin + offset`` for each offset."""
        return cls(
            (float(origin[0]), float(origin[1])), tuple((float(p[0]), float(p[1])) for p in offsets)
        )

    def vertices(self) -> list[Point]:
        """The polyline's corners, origin first."""
        ox, oy = self.origin
        return [self.origin, *((ox + dx, oy + dy) for dx, dy in self.points)]

    def heading(self) -> float:
        """Direction of the first segment."""
        v = self.vertices()
        return math.atan2(v[1][1] - v[0][1], v[1][0] - v[0][0])

    def length(self) -> float:
        """Total length."""
        v = self.vertices()
        return sum(math.dist(a, b) for a, b in itertools.pairwise(v))

    def shifted(self, offset: Point) -> Path:
        """The same path started at ``origin + offset`` (a robot's own track)."""
        return Path((self.origin[0] + offset[0], self.origin[1] + offset[1]), self.points)

    def locate(self, p: Sequence[float]) -> tuple[float, float, float]:
        """(progress along the path, cross-track error left-positive, path heading there)."""
        v = self.vertices()
        best = (math.inf, 0.0, 0.0, 0.0)
        done = 0.0
        for a, b in itertools.pairwise(v):
            dx, dy = b[0] - a[0], b[1] - a[1]
            seg = math.hypot(dx, dy)
            if seg == 0:
                continue
            t = clip(((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (seg * seg), 0.0, 1.0)
            qx, qy = a[0] + t * dx, a[1] + t * dy
            d = math.hypot(p[0] - qx, p[1] - qy)
            if d < best[0] - 1e-9:
                cross = (dx * (p[1] - a[1]) - dy * (p[0] - a[0])) / seg
                best = (d, done + t * seg, cross, math.atan2(dy, dx))
            done += seg
        # beyond the end: count the overshoot along the last segment as progress
        a, b = v[-2], v[-1]
        seg = math.dist(a, b)
        if seg > 0:
            along = ((p[0] - b[0]) * (b[0] - a[0]) + (p[1] - b[1]) * (b[1] - a[1])) / seg
            if along > 0 and best[1] >= done - 1e-9:
                return done + along, best[2], best[3]
        return best[1], best[2], best[3]


def stations(
    winner: str, members: Sequence[str], width: float, margin: float = 0.18
) -> dict[str, tuple[str, float]]:
    """Who does what and where: ``{member: (role, lateral offset)}`` along the rear face.

    The finder is the pusher (section 4.2, item 6) at the right rear corner; the others are
    steerers spread evenly to the left corner. Offsets are left-positive, facing the path.
    """
    others = [m for m in sorted(members) if m != winner]
    n = len(others) + 1
    half = max(width / 2.0 - margin, 0.0)
    laterals = [-half + 2.0 * half * i / (n - 1) for i in range(n)] if n > 1 else [0.0]
    out = {winner: ("pusher", laterals[0])}
    for m, lat in zip(others, laterals[1:], strict=True):
        out[m] = ("steerer", lat)
    return out


def sighting_of(
    sightings: Sequence[Sighting], object_id: str | None, kind: str = "box"
) -> Sighting | None:
    """The sighting of the object being moved (by id, else the nearest of ``kind``)."""
    for s in sightings:
        if (s.id == object_id) if object_id is not None else (s.kind == kind):
            return s
    return None


def object_pose(pose: Pose, seen: Sighting, bearing0: float) -> Pose:
    """The object's (x, y, heading) from a sighting, given the world angle ``bearing0`` under
    which the robot saw the centre relative to the object's heading at the start."""
    angle = pose[2] + seen.bearing
    x = pose[0] + seen.range * math.cos(angle)
    y = pose[1] + seen.range * math.sin(angle)
    return (x, y, wrap(angle - bearing0))


def align(seen: Sighting | None, bearing0: float, gain: float = 2.0) -> float:
    """Turn rate that keeps the object's centre at the bearing it had at the start (the robot
    stays square to the face as the object turns)."""
    if seen is None:
        return 0.0
    return clip(gain * wrap(seen.bearing - bearing0), -0.8, 0.8)


def pusher_command(
    seen: Sighting | None, bearing0: float, speed: float = 0.3
) -> tuple[float, float]:
    """The pusher: constant speed, square to the face."""
    return speed, align(seen, bearing0)


def steerer_command(
    path: Path,
    box: Pose | None,
    lateral: float,
    seen: Sighting | None,
    bearing0: float,
    *,
    speed: float = 0.3,
    authority: float = 0.2,
    k_cross: float = 0.8,
    k_heading: float = 0.6,
) -> tuple[float, float]:
    """The steerer: the pusher's speed ±``authority``, to turn the object toward the path.

    The desired object heading is the path's, turned toward the path by the object's
    cross-track error; a robot right of the centre (``lateral`` < 0) speeds up to turn the
    object left, one on the left slows down.
    """
    if box is None:
        return speed, 0.0
    _, cross, heading = path.locate(box)
    desired = heading - clip(k_cross * cross, -0.5, 0.5)
    err = wrap(desired - box[2])
    side = -math.copysign(1.0, lateral) if abs(lateral) > 1e-6 else 0.0
    dv = clip(side * k_heading * err * 2.0, -authority, authority)
    return speed + dv, align(seen, bearing0)


# -- procedures ------------------------------------------------------------------------------


def _sightings(robot: Robot) -> tuple[Sighting, ...]:
    return robot.hw.camera.sightings() if robot.hw.camera is not None else ()


async def _manipulate(
    robot: Robot,
    path: Path,
    lateral: float,
    object_id: str | None,
    steer: bool,
    speed: float,
    timeout: float,
) -> dict[str, Any]:
    hw = robot.hw
    start = hw.odometry.pose()
    track = path.shifted((start[0] - path.origin[0], start[1] - path.origin[1]))
    first = sighting_of(_sightings(robot), object_id)
    bearing0 = first.bearing if first is not None else 0.0
    world0 = (start[2] + first.bearing - path.heading()) if first is not None else 0.0
    end = hw.clock.now() + timeout
    box: Pose | None = None
    progress = 0.0
    try:
        while hw.clock.now() < end:
            pose = hw.odometry.pose()
            progress = track.locate(pose)[0]
            if progress >= track.length():
                break
            seen = sighting_of(_sightings(robot), object_id)
            box = object_pose(pose, seen, world0) if seen is not None else None
            if steer:
                v, w = steerer_command(path, box, lateral, seen, bearing0, speed=speed)
            else:
                v, w = pusher_command(seen, bearing0, speed)
            hw.drive.set_velocity(v, w)
            await hw.clock.tick()
        moved = math.dist(box[:2], path.origin) if box is not None else progress
        return {
            "progress": progress,
            "done": progress >= track.length(),
            "moved": moved,
            "object": list(box) if box is not None else None,
            "pose": list(hw.odometry.pose()),
        }
    finally:
        hw.drive.stop()


async def pusher(
    robot: Robot,
    path: Path,
    *,
    object_id: str | None = None,
    speed: float = 0.3,
    timeout: float = 120.0,
) -> dict[str, Any]:
    """Push the object along ``path`` at a constant speed, staying square to its face
    (section 4.3, ``pusher``); stops when this robot has gone the path's length.

    Returns ``{"progress", "done", "moved", "object", "pose"}`` (odometry frame): ``moved``
    is how far the object is from the path's origin as the camera sees it at the end, else
    this robot's progress.
    """
    return await _manipulate(robot, path, 0.0, object_id, False, speed, timeout)


async def steerer(
    robot: Robot,
    path: Path,
    lateral: float,
    *,
    object_id: str | None = None,
    speed: float = 0.3,
    timeout: float = 120.0,
) -> dict[str, Any]:
    """Steer the object along ``path`` from ``lateral`` m left of its centre line (section
    4.3, ``steerer``): the pusher's speed, ±0.2 m/s to turn the object toward the path.

    Returns ``{"progress", "done", "moved", "object", "pose"}`` as :func:`pusher` does.
    """
    return await _manipulate(robot, path, lateral, object_id, True, speed, timeout)
