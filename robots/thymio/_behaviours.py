"""Behaviours and procedures for a robot whose range sensors reach only a few centimetres.

The library's wander (``robots.library.Wander``) waits for the bumper and its go-to repels from
anything within 45 cm; a Thymio has no bumper and sees 10 cm. :class:`ProxWander` is a
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

    ``step(ranges, angles, reach)`` → (v, w). Each front sensor that sees something within
    ``reach`` turns the robot away from its side (a centre one: the side the robot last
    turned to) and slows it; with nothing in sight it drives at ``speed`` and draws a new
    turn rate from ``rng`` every ``every`` steps.
    """

    def __init__(
        self, rng: _Rng, *, speed: float = 0.1, turn: float = 2.5, every: int = 40
    ) -> None:
        self.rng, self.speed, self.turn, self.every = rng, speed, turn, every
        self.side = 1.0
        self.drift = 0.0
        self.steps = 0

    def step(
        self, ranges: Sequence[float], angles: Sequence[float], reach: float
    ) -> tuple[float, float]:
        """The next (v m/s, w rad/s)."""
        self.steps += 1
        push, near = 0.0, 0.0
        for r, a in zip(ranges, angles, strict=True):
            if abs(a) > math.pi / 2 or r >= reach:
                continue
            closeness = 1.0 - r / reach
            near = max(near, closeness)
            side = math.copysign(1.0, a) if a != 0 else self.side
            push -= side * closeness
        if near > 0:
            self.side = -1.0 if push < 0 else 1.0
            return self.speed * max(0.0, 1.0 - 1.5 * near), self.turn * (push or self.side)
        if self.steps % self.every == 1:
            self.drift = self.rng.uniform(-0.8, 0.8)
        return self.speed, self.drift


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
