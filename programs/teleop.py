"""teleop: drive one robot by hand; the program `mover drive ROBOT` starts on it.

The robot listens on ``f"{topic}/{robot.id}"`` for commands from members of its team: ``[v, w]``
(forward speed in m/s, turn rate in rad/s, clipped to the drive's bounds) or ``"quit"``. A
command holds for ``hold`` wall seconds and then the robot stops (a dead man's switch: a lost
key release or a launcher that went away never leaves it driving). The run ends on ``"quit"``
or when no command came for ``idle`` wall seconds, and returns where the robot thinks it is.

Why wall time here, unlike every other program: the driver is a person. A lock-step world
runs as fast as its robots tick, so the program paces its ticks to ``pace`` simulated seconds
per wall second; the run's outcome then depends on the keys and their timing, as it should.
"""

from __future__ import annotations

import asyncio
import time
from typing import Any

from mover import RunTeam
from robots import Robot


def command(data: object, max_speed: float, max_turn: float) -> tuple[float, float] | None:
    """``[v, w]`` clipped to the bounds, or None for anything else (``"quit"`` included)."""
    if not isinstance(data, list | tuple) or len(data) != 2:
        return None
    if not all(isinstance(x, int | float) and not isinstance(x, bool) for x in data):
        return None
    v, w = float(data[0]), float(data[1])
    return (max(-max_speed, min(max_speed, v)), max(-max_turn, min(max_turn, w)))


async def teleop(
    robot: Robot,
    team: RunTeam,
    topic: str = "teleop",
    hold: float = 0.5,
    idle: float = 300.0,
    pace: float = 1.0,
    max_turn: float = 1.5,
) -> dict[str, Any]:
    """Apply the commands heard on ``topic/<robot>`` until ``"quit"`` or ``idle`` s of none."""
    hw, node = robot.hw, robot.node
    assert node is not None, "teleop runs in a robot process"
    commands = node.subscribe(f"{topic}/{robot.id}")
    await team.report("driving", topic=f"{topic}/{robot.id}")
    wall0, sim0 = time.monotonic(), hw.clock.now()
    last = wall0
    moves = 0
    try:
        while True:
            for message in commands.drain():
                if message.data == "quit":
                    return {"pose": [round(x, 3) for x in hw.odometry.pose()], "moves": moves}
                cmd = command(message.data, hw.drive.max_speed, max_turn)
                if cmd is not None:
                    hw.drive.set_velocity(*cmd)
                    last, moves = time.monotonic(), moves + 1
            now = time.monotonic()
            if now - last > hold:
                hw.drive.stop()
            if now - last > idle:
                return {"pose": [round(x, 3) for x in hw.odometry.pose()], "moves": moves}
            await hw.clock.tick()
            ahead = (hw.clock.now() - sim0) / pace - (time.monotonic() - wall0)
            if ahead > 0:
                await asyncio.sleep(ahead)  # a person drives: simulated time at wall pace
    finally:
        hw.drive.stop()
        commands.close()
