"""A cancelled procedure leaves the robot still (its ``finally`` stops the motors): what a
loser of ``distributed_or`` relies on."""

from __future__ import annotations

import asyncio
import math
import random
from collections.abc import Awaitable, Callable

import pytest

from robots import Robot
from robots.library import Path, goto_object, pusher, search, sees
from sim_hw import World, WorldSpec

from .conftest import robots_in


def procedures(robot: Robot) -> dict[str, Callable[[], Awaitable[object]]]:
    return {
        "search": lambda: search(robot, sees("box"), rng=random.Random(0)),
        "goto_object": lambda: goto_object(robot, (4.5, 3.0), math.pi, 0.0),
        "pusher": lambda: pusher(robot, Path.relative((4.5, 3.0), [(3.0, 0.0)])),
    }


@pytest.mark.parametrize("name", ["search", "goto_object", "pusher"])
async def test_cancelled_procedures_stop_the_motors(demo: WorldSpec, name: str) -> None:
    world = World(demo, seed=0)
    server, robots = await robots_in(world, {"ernst": None})
    robot = robots["ernst"]
    spawn = world.pose("ernst")
    task = asyncio.ensure_future(procedures(robot)[name]())
    while robot.hw.clock.now() < 3.0:  # let it get going (the world steps as it ticks)
        await asyncio.sleep(0)
    going = world.pose("ernst")
    assert math.dist(spawn[:2], going[:2]) > 0.05 or abs(going[2] - spawn[2]) > 0.05
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    await robot.hw.clock.tick()  # the stop command goes out
    before = world.pose("ernst")
    await robot.hw.clock.sleep(1.0)
    after = world.pose("ernst")
    await server.door.aclose()
    assert math.dist(before[:2], after[:2]) < 0.01 and abs(after[2] - before[2]) < 0.01
