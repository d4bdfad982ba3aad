"""goto_object and goto_point (section 4.3) in the demo world: dead reckoning, sonar
avoidance, the detour round the object and the cautious final approach."""

from __future__ import annotations

import math

import pytest

from robots.library import goto_object, goto_point
from sim_hw import World, WorldSpec

from .conftest import robots_in


@pytest.mark.parametrize(
    ("robot_id", "heading", "lateral"),
    [
        ("ernst", 0.0, 0.42),  # straight ahead, to the left corner of the rear face
        ("moseley", math.pi, -0.42),  # round the box, to its far (east) face
    ],
)
async def test_goto_object_ends_against_the_object(
    demo: WorldSpec, robot_id: str, heading: float, lateral: float
) -> None:
    world = World(demo, seed=1)
    server, robots = await robots_in(world, {robot_id: None})
    robot = robots[robot_id]
    estimate = (4.45, 3.05)  # where a finder thought the box was: 7 cm off
    got = await goto_object(robot, estimate, heading, lateral, object_id="victim")
    x, y, th = world.pose(robot_id)
    bx, by, _ = world.box_pose("victim")
    # the expected place: touching the face (half depth 0.3 + radius 0.15), lateral to its left
    ex = bx - math.cos(heading) * 0.45 - math.sin(heading) * lateral
    ey = by - math.sin(heading) * 0.45 + math.cos(heading) * lateral
    print(
        f"\ngoto_object ({robot_id}): {robot.hw.clock.now():.1f} s, at ({x:.3f}, {y:.3f}, "
        f"{th:.3f}), expected ({ex:.3f}, {ey:.3f}, {heading:.3f}), {got}"
    )
    await server.door.aclose()
    assert got["arrived"] and got["contact"]
    assert math.dist((x, y), (ex, ey)) < 0.08
    assert abs(math.remainder(th - heading, math.tau)) < 0.05
    assert robot.hw.clock.now() < 60


async def test_goto_point_avoids_an_obstacle_in_the_way(demo: WorldSpec) -> None:
    world = World(demo, seed=1)
    server, robots = await robots_in(world, {"elvis": None})  # at (0.8, 1.0), a wall at x=2.5
    robot = robots["elvis"]
    assert await goto_point(robot, (4.0, 1.2), timeout=60.0)
    x, y, _ = world.pose("elvis")
    print(f"\ngoto_point: {robot.hw.clock.now():.1f} s, at ({x:.3f}, {y:.3f})")
    await server.door.aclose()
    assert math.dist((x, y), (4.0, 1.2)) < 0.12
