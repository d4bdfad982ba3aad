"""levy_search on the HAL of an in-process world: each walk finds a target in the open."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robots.library import METHODS, levy_search, walker
from sim_hw import CameraSpec, MarkerSpec, RobotSpec, SonarSpec, World, WorldSpec

from .conftest import robots_in

ROBOT = RobotSpec(
    max_speed=0.6,
    sonar=SonarSpec(rays=8, max_range=1.0),
    camera=CameraSpec(max_range=3.0, fov=2 * math.pi),
)


@pytest.mark.parametrize("method", METHODS)
async def test_each_walk_finds_a_target_in_the_open(method: str) -> None:
    spec = WorldSpec(
        size=(6.0, 6.0),
        robot=ROBOT,
        markers=(MarkerSpec("target", "t0", (4.5, 4.0), 0.2, "", 1.15),),
    )
    world = World(spec, seed=1)
    server, robots = await robots_in(world, {"r0": {"pose": [1.0, 1.0, 0.3]}})
    robot = robots["r0"]
    walk = walker(method, np.random.default_rng(3))
    marked = await levy_search(
        robot, walk, terminator=lambda: bool(world.marked) or world.time > 600
    )
    assert marked == {"t0"} and set(world.marked) == {"t0"}
    assert 3.0 < world.marked["t0"] < 600, world.marked
    x, y, _ = world.pose("r0")
    assert math.hypot(x - 4.5, y - 4.0) <= 1.15
    await robot.hw.clock.tick()
    assert world.robots["r0"].v == 0.0  # stopped on the way out
    sightings = robot.hw.camera.sightings() if robot.hw.camera else ()
    assert [s.status for s in sightings if s.id == "t0"] == ["marked"]
    await server.door.aclose()
