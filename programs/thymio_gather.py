"""thymio_gather: Thymios search a dark patch of floor, then gather around it and light up.

Every robot wanders, avoiding obstacles with its proximity sensors, until one's ground
sensors find a dark floor — ``distributed_or``: the first wins, the others stop. Every robot
then drives to its own place around the patch (the finder's odometry, in the frame the team
file's poses give) and waits for the others — ``distributed_and``. All show green on their
top LED; the finder's ring lights too.
"""

from __future__ import annotations

import math
from typing import Any

from mover import RunTeam
from robots import Robot
from robots.library import needs
from robots.thymio import ProxWander, ThymioHardware, drive_to, wander_until

#: The ground sensors sit this far ahead of the wheels' axis (metres).
SENSORS_AHEAD = 0.07


@needs("ground", "sonar", "leds")  # checked as it starts: one line on a robot without
async def thymio_gather(
    robot: Robot[ThymioHardware],
    team: RunTeam,
    speed: float = 0.12,
    ring: float = 0.2,
    timeout: float = 120.0,
) -> dict[str, Any]:
    """Find the dark patch, stand ``ring`` metres from it around it, light green.

    The search gives up after ``timeout`` seconds (its result then None: no patch); a robot
    that has not reached its place within ``timeout / 3`` seconds stays where it is."""
    hw = robot.hw
    hw.leds.show("blue")
    await team.report("searching")
    wander = ProxWander(team.rng("wander"), speed=speed)
    won = await team.distributed_or(
        lambda: wander_until(robot, hw.ground.dark, wander, timeout=timeout)
    )
    if won.result is None:
        hw.leds.show("red")
        await hw.clock.tick()
        return {"winner": None, "patch": None, "pose": list(hw.odometry.pose())}
    x, y, th = won.result
    patch = (x + SENSORS_AHEAD * math.cos(th), y + SENSORS_AHEAD * math.sin(th))
    await team.report("found", winner=won.winner, patch=[round(patch[0], 3), round(patch[1], 3)])
    hw.leds.show("yellow")
    others = [m for m in team.members if m != won.winner]
    if team.me != won.winner:
        a = 2 * math.pi * others.index(team.me) / max(len(others), 1)
        place = (patch[0] + ring * math.cos(a), patch[1] + ring * math.sin(a))
        await team.distributed_and(lambda: drive_to(robot, place, speed=speed, timeout=timeout / 3))
    else:
        await team.distributed_and(lambda: _stay())
    hw.leds.show("green")
    if team.me == won.winner:
        hw.leds.circle((32,) * 8)
    await hw.clock.tick()  # the lights go out with this tick's commands
    pose = hw.odometry.pose()
    return {
        "winner": won.winner,
        "patch": list(patch),
        "pose": list(pose),
        "from_patch": math.dist(pose[:2], patch),
    }


async def _stay() -> bool:
    return True
