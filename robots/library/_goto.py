"""MOVER's ``goto-object`` (Jennings et al., section 4.3): dead reckoning to a point near the
object, around it if need be, with sonar obstacle avoidance; then a cautious approach to a
pose against it with the requested final heading (section 4.1 "Navigation": online, no map).

Decision rules: :func:`steer` (go-to-point with sonar repulsion), :func:`detour` (waypoints
around the object on the shorter side), :func:`station` (where to stand against the object).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from robots._robot import Robot

from ._geometry import Point, Pose, bearing_to, clip, distance, to_frame, wrap


def steer(
    pose: Pose,
    target: Point,
    ranges: Sequence[float],
    angles: Sequence[float],
    *,
    speed: float = 0.4,
    avoid_range: float = 0.45,
    gain: float = 2.5,
    max_turn: float = 1.5,
) -> tuple[float, float]:
    """(v, w) toward ``target``, pushed away from what the sonar sees within ``avoid_range``.

    The attraction is a unit vector to the target; each close ray adds a repulsion growing as
    the range shrinks, faded out in the last half metre so that the robot can stop next to
    things (the object, teammates) at its goal.
    """
    dist = distance(pose, target)
    b = bearing_to(pose, target)
    fade = clip(dist / 0.5, 0.0, 1.0)
    rx = ry = 0.0
    for r, a in zip(ranges, angles, strict=False):
        if r < avoid_range:
            k = (avoid_range - r) / avoid_range
            rx -= k * math.cos(a)
            ry -= k * math.sin(a)
    dx, dy = math.cos(b) + 1.5 * fade * rx, math.sin(b) + 1.5 * fade * ry
    desired = math.atan2(dy, dx)
    front = _ahead(ranges, angles, avoid_range)
    slow = clip((front - 0.03) / avoid_range, 0.0, 1.0) if fade > 0.5 else 1.0
    v = speed * max(0.0, math.cos(desired)) * max(slow, 0.15) * clip(dist / 0.3, 0.2, 1.0)
    if abs(desired) > 1.2:
        v = 0.0  # turn on the spot first
    return v, clip(gain * desired, -max_turn, max_turn)


def _ahead(ranges: Sequence[float], angles: Sequence[float], none: float) -> float:
    """The shortest range of the rays within 0.8 rad of straight ahead (``none`` if none)."""
    return min(
        (r for r, a in zip(ranges, angles, strict=False) if abs(wrap(a)) < 0.8), default=none
    )


def detour(
    start: Point, goal: Point, center: Point, radius: float, step: float = math.pi / 4
) -> list[Point]:
    """Waypoints from ``start`` to ``goal`` that stay ``radius`` away from ``center``.

    If the straight segment clears the circle, just ``[goal]``; otherwise points on the circle,
    going round the shorter way, then ``goal``.
    """
    if _clears(start, goal, center, radius):
        return [goal]
    a0 = math.atan2(start[1] - center[1], start[0] - center[0])
    a1 = math.atan2(goal[1] - center[1], goal[0] - center[0])
    sweep = wrap(a1 - a0)
    n = max(1, math.ceil(abs(sweep) / step))
    points = [
        (
            center[0] + radius * math.cos(a0 + sweep * i / n),
            center[1] + radius * math.sin(a0 + sweep * i / n),
        )
        for i in range(1, n + 1)
    ]
    return [*points, goal]


def _clears(a: Point, b: Point, c: Point, r: float) -> bool:
    ax, ay = b[0] - a[0], b[1] - a[1]
    length2 = ax * ax + ay * ay
    t = 0.0 if length2 == 0 else clip(((c[0] - a[0]) * ax + (c[1] - a[1]) * ay) / length2, 0, 1)
    return math.hypot(a[0] + t * ax - c[0], a[1] + t * ay - c[1]) >= r


def station(location: Point, heading: float, lateral: float, standoff: float) -> Pose:
    """The pose ``standoff`` m behind ``location`` (against ``heading``), ``lateral`` m to its
    left, facing ``heading``: where a robot waits before the cautious approach."""
    x, y = to_frame((location[0], location[1], heading), (-standoff, lateral))
    return (x, y, heading)


# -- procedures ------------------------------------------------------------------------------


def _sonar(robot: Robot) -> tuple[tuple[float, ...], tuple[float, ...]]:
    sonar = robot.hw.sonar
    if sonar is None:
        return (), ()
    return sonar.ranges(), sonar.angles


def sidestep(
    pose: Pose,
    target: Point,
    ranges: Sequence[float],
    angles: Sequence[float],
    *,
    reach: float = 0.9,
    blocked: float = 0.3,
) -> Point | None:
    """A way round an obstacle between the robot and ``target``, or None if the way is free.

    When the sonar sees something within ``blocked`` m in front while the target is roughly
    ahead (where plain repulsion stalls), the robot aims at a point ``reach`` m away, 70° to
    the side with more room (a small step of the bug algorithms).
    """
    b = bearing_to(pose, target)
    front = _ahead(ranges, angles, math.inf)
    if front > blocked or abs(b) > 1.2 or distance(pose, target) < front + 0.3:
        return None
    left = sum(r for r, a in zip(ranges, angles, strict=False) if 0.3 < wrap(a) < 2.0)
    right = sum(r for r, a in zip(ranges, angles, strict=False) if -2.0 < wrap(a) < -0.3)
    side = 1.0 if left >= right else -1.0
    heading = pose[2] + b + side * math.radians(70)
    return (pose[0] + reach * math.cos(heading), pose[1] + reach * math.sin(heading))


async def goto_point(
    robot: Robot,
    target: Point,
    *,
    speed: float = 0.4,
    tolerance: float = 0.08,
    timeout: float = 60.0,
) -> bool:
    """Drive to ``target`` (odometry frame) avoiding obstacles; False if not there in time."""
    hw = robot.hw
    end = hw.clock.now() + timeout
    aim: Point = target
    detour_until = 0.0
    try:
        while hw.clock.now() < end:
            pose = hw.odometry.pose()
            if distance(pose, target) < tolerance:
                return True
            ranges, angles = _sonar(robot)
            if aim != target and (hw.clock.now() > detour_until or distance(pose, aim) < 0.15):
                aim = target
            if aim == target:
                side = sidestep(pose, target, ranges, angles)
                if side is not None:
                    aim, detour_until = side, hw.clock.now() + 6.0
            hw.drive.set_velocity(*steer(pose, aim, ranges, angles, speed=speed))
            await hw.clock.tick()
        return False
    finally:
        hw.drive.stop()


async def turn_to(
    robot: Robot, heading: float, *, tolerance: float = 0.03, timeout: float = 10.0
) -> None:
    """Turn on the spot to ``heading`` (odometry frame)."""
    hw = robot.hw
    end = hw.clock.now() + timeout
    try:
        while hw.clock.now() < end:
            err = wrap(heading - hw.odometry.pose()[2])
            if abs(err) < tolerance:
                return
            hw.drive.set_velocity(0.0, clip(3.0 * err, -1.2, 1.2))
            await hw.clock.tick()
    finally:
        hw.drive.stop()


async def approach(robot: Robot, heading: float, *, speed: float = 0.1, limit: float = 1.0) -> bool:
    """The cautious approach: creep along ``heading`` until the front bumper touches."""
    hw = robot.hw
    start = hw.odometry.pose()
    end = hw.clock.now() + 2.0 * limit / speed
    try:
        while hw.clock.now() < end and distance(hw.odometry.pose(), start) < limit:
            if hw.bumper is not None and hw.bumper.side() == "front":
                return True
            err = wrap(heading - hw.odometry.pose()[2])
            hw.drive.set_velocity(speed, clip(3.0 * err, -0.5, 0.5))
            await hw.clock.tick()
        return False
    finally:
        hw.drive.stop()


def _refine(robot: Robot, object_id: str | None, location: Point) -> Point:
    """The object's centre as the camera sees it now (if it is seen), else ``location``."""
    cam = robot.hw.camera
    if object_id is None or cam is None:
        return location
    pose = robot.hw.odometry.pose()
    for s in cam.sightings():
        if s.id == object_id:
            return (
                pose[0] + s.range * math.cos(pose[2] + s.bearing),
                pose[1] + s.range * math.sin(pose[2] + s.bearing),
            )
    return location


async def goto_object(
    robot: Robot,
    location: Sequence[float],
    heading: float,
    lateral: float = 0.0,
    *,
    object_id: str | None = None,
    standoff: float = 0.9,
    clearance: float = 1.0,
    timeout: float = 120.0,
) -> dict[str, Any]:
    """Go to the object at ``location`` and stand against it facing ``heading`` (section 4.3).

    The robot drives (round the object if needed, ``clearance`` m from its centre) to a point
    ``standoff`` m behind it and ``lateral`` m to the left, faces ``heading``, corrects the
    point once with the camera if it sees ``object_id``, then creeps forward until the bumper
    touches. Returns ``{"arrived", "contact", "location", "pose"}`` (odometry frame).
    """
    hw = robot.hw
    loc = (float(location[0]), float(location[1]))
    end = hw.clock.now() + timeout
    arrived = False
    try:
        for _ in range(2):  # the second pass uses the camera's correction of the location
            goal = station(loc, heading, lateral, standoff)
            for waypoint in detour(hw.odometry.pose()[:2], goal[:2], loc, clearance):
                left = max(end - hw.clock.now(), 1.0)
                arrived = await goto_point(robot, waypoint, timeout=left)
            await turn_to(robot, heading)
            seen = _refine(robot, object_id, loc)
            if distance(seen, loc) < 0.05:
                break
            loc = seen
        contact = await approach(robot, heading, limit=standoff)
        return {
            "arrived": arrived,
            "contact": contact,
            "location": list(loc),
            "pose": list(hw.odometry.pose()),
        }
    finally:
        hw.drive.stop()


def follow_command(
    seen_range: float | None, seen_bearing: float, *, gap: float = 0.7, speed: float = 0.35
) -> tuple[float, float]:
    """Keep ``gap`` m behind a leader seen at (range, bearing); turn to look for it if unseen
    (section 5: the trainee follows the trainer)."""
    if seen_range is None:
        return 0.0, 0.8
    v = clip(1.2 * (seen_range - gap), 0.0, speed) if abs(seen_bearing) < 1.0 else 0.0
    return v, clip(2.5 * seen_bearing, -1.5, 1.5)


async def follow(robot: Robot, leader: str, *, gap: float = 0.7, speed: float = 0.35) -> None:
    """Follow the robot ``leader`` with the camera until cancelled (motors stop then)."""
    hw = robot.hw
    try:
        while True:
            seen = next(
                (
                    s
                    for s in (hw.camera.sightings() if hw.camera else ())
                    if s.kind == "robot" and s.id == leader
                ),
                None,
            )
            hw.drive.set_velocity(
                *follow_command(
                    seen.range if seen else None,
                    seen.bearing if seen else 0.0,
                    gap=gap,
                    speed=speed,
                )
            )
            await hw.clock.tick()
    finally:
        hw.drive.stop()
