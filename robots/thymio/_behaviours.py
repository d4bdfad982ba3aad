"""Behaviours and procedures for a robot whose range sensors reach only a few centimetres.

The library's wander (``robots.library.Wander``) waits for the bumper and its go-to repels from
anything within 45 cm; a Thymio has no bumper and sees 12 cm. :class:`ProxWander` is a
Braitenberg vehicle instead (turn away from what the front sensors see, slow down as it
nears, change heading now and then); :func:`wander_until` and :func:`drive_to` run it and
the library's ``steer`` (with the sensors' own reach) on the HAL, stopping the motors in
their ``finally``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol, TypeVar

from robots._robot import Robot
from robots.hal import Hardware, Pose
from robots.library import steer

__all__ = ["ProxWander", "drive_to", "wander_until"]


HW = TypeVar("HW", bound=Hardware)


class _Rng(Protocol):
    def uniform(self, a: float, b: float) -> float: ...


class ProxWander:
    """Wander, avoiding what the proximity sensors see (see the module docstring).

    ``step(ranges, angles, reach)`` → (v, w). When a front sensor sees something within
    ``reach``, the robot picks a side to turn to — away from the side that sees more, or at
    random when both see as much (a wall straight ahead) — and keeps turning that way, slowing
    as it nears and backing off at contact, until nothing is in sight: a side chosen afresh
    each step would flip back and forth in front of a wall. With nothing in sight it drives
    at ``speed`` and draws a new turn rate from ``rng`` every ``every`` steps.
    """

    def __init__(
        self, rng: _Rng, *, speed: float = 0.1, turn: float = 2.0, every: int = 40
    ) -> None:
        self.rng, self.speed, self.turn, self.every = rng, speed, turn, every
        self.turning = 0.0  # the side being turned to while avoiding (+1 left, -1 right)
        self.drift = 0.0
        self.steps = 0

    def step(
        self, ranges: Sequence[float], angles: Sequence[float], reach: float
    ) -> tuple[float, float]:
        """The next (v m/s, w rad/s)."""
        self.steps += 1
        left, near = 0.0, 0.0  # how much more the left sees than the right; the closest
        for r, a in zip(ranges, angles, strict=True):
            if abs(a) > math.pi / 2 or r >= reach:
                continue
            closeness = 1.0 - r / reach
            near = max(near, closeness)
            left += closeness * (1.0 if a > 0 else -1.0 if a < 0 else 0.0)
        if near == 0.0:
            self.turning = 0.0
            if self.steps % self.every == 1:
                self.drift = self.rng.uniform(-0.8, 0.8)
            return self.speed, self.drift
        if self.turning == 0.0:
            if abs(left) > 0.05:
                self.turning = -1.0 if left > 0 else 1.0
            else:
                self.turning = 1.0 if self.rng.uniform(-1.0, 1.0) >= 0 else -1.0
        # Slower as it nears; backing off a little at contact, where a corner of the body
        # can wedge a turn on the spot against a wall or a teammate.
        v = self.speed * max(-0.3, 1.0 - 1.5 * near)
        return v, self.turn * self.turning


async def wander_until(
    robot: Robot[HW], done: Callable[[], bool], wander: ProxWander, *, timeout: float = 300.0
) -> Pose | None:
    """Wander until ``done()`` (checked each tick); the pose then, or None after ``timeout``
    seconds."""
    hw = robot.hw
    sonar = hw.sonar
    end = hw.clock.now() + timeout
    try:
        while hw.clock.now() < end:
            if done():
                return hw.odometry.pose()
            ranges = sonar.ranges() if sonar is not None else ()
            angles = sonar.angles if sonar is not None else ()
            reach = sonar.max_range if sonar is not None else 0.0
            hw.drive.set_velocity(*wander.step(ranges, angles, reach))
            await hw.clock.tick()
        return None
    finally:
        hw.drive.stop()


async def drive_to(
    robot: Robot[HW],
    target: tuple[float, float],
    *,
    speed: float = 0.1,
    tolerance: float = 0.05,
    timeout: float = 60.0,
) -> bool:
    """Drive to ``target`` (odometry frame), turning from what the sensors see; False if not
    there within ``timeout`` seconds."""
    hw = robot.hw
    sonar = hw.sonar
    end = hw.clock.now() + timeout
    try:
        while hw.clock.now() < end:
            pose = hw.odometry.pose()
            if math.dist(pose[:2], target) < tolerance:
                return True
            ranges = sonar.ranges() if sonar is not None else ()
            angles = sonar.angles if sonar is not None else ()
            reach = 0.9 * sonar.max_range if sonar is not None else 0.0
            v, w = steer(pose, target, ranges, angles, speed=speed, avoid_range=reach)
            hw.drive.set_velocity(v, w)
            await hw.clock.tick()
        return False
    finally:
        hw.drive.stop()
