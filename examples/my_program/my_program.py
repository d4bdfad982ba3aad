"""race: every robot drives straight on; the first to cover ``distance`` metres wins.

A template for a program of your own: an ``async def`` taking the robot (its hardware, through
the HAL) and the team (the collectives), plus data arguments, installed through the
``mover.programs`` entry point (see pyproject.toml).
"""

from __future__ import annotations

import math
from typing import Any

from mover import RunTeam
from robots import Robot


async def race(robot: Robot, team: RunTeam, distance: float = 1.0) -> dict[str, Any]:
    """Drive at a seeded speed until ``distance`` metres are covered; who was first?"""
    hw = robot.hw
    speed = 0.2 + 0.2 * team.rng("speed").random()  # every random choice from the run's seed

    async def drive() -> float:
        x0, y0, _ = hw.odometry.pose()
        hw.drive.set_velocity(speed, 0.0)
        while math.dist(hw.odometry.pose()[:2], (x0, y0)) < distance:
            await hw.clock.tick()
        hw.drive.stop()
        return hw.clock.now()

    try:
        won = await team.distributed_or(drive)
    finally:
        hw.drive.stop()
    await team.report("done", winner=won.winner)
    return {"winner": won.winner, "at": won.result, "my_speed": round(speed, 3)}
