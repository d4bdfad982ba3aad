"""Pusher and steerer (section 4.3, after [BJ95]) on the demo world's 2-robot box: two robots
move it along the path; one alone only pivots it."""

from __future__ import annotations

import math

from robots.library import Path, pusher, steerer
from sim_hw import World, WorldSpec

from .conftest import robots_in, together

BOX = (4.5, 3.0)  # the demo box: 0.6 m deep along the path, 1.2 m wide
REAR = BOX[0] - 0.3 - 0.15 - 0.01  # a robot's centre just behind the rear face


def along(world: World, path: Path) -> float:
    """How far the box went along the path's first segment."""
    x, y, _ = world.box_pose("victim")
    h = path.heading()
    return (x - BOX[0]) * math.cos(h) + (y - BOX[1]) * math.sin(h)


async def test_pusher_and_steerer_move_the_box_along_the_path(demo: WorldSpec) -> None:
    world = World(demo, seed=1)
    settings = {
        "elvis": {"pose": [REAR, BOX[1] - 0.42, 0.0]},  # right corner: pusher
        "ernst": {"pose": [REAR, BOX[1] + 0.42, 0.0]},
    }  # left corner: steerer
    server, robots = await robots_in(world, settings)
    path = Path.relative(BOX, [(3.0, 0.0)])
    results = await together(
        {
            "elvis": lambda: pusher(robots["elvis"], path, object_id="victim", timeout=40.0),
            "ernst": lambda: steerer(robots["ernst"], path, 0.42, object_id="victim", timeout=40.0),
        },
        robots,
    )
    x, y, th = world.box_pose("victim")
    t = robots["elvis"].hw.clock.now()
    print(
        f"\npusher+steerer: box at ({x:.2f}, {y:.2f}, {th:.3f}) after {t:.1f} s simulated, "
        f"{along(world, path):.2f} m along the path; {results}"
    )
    await server.door.aclose()
    assert along(world, path) >= 2.0
    assert abs(y - BOX[1]) < 0.25 and abs(th) < 0.2
    assert all(r["done"] for r in results.values())


async def test_a_curved_path(demo: WorldSpec) -> None:
    world = World(demo, seed=1)
    settings = {
        "elvis": {"pose": [REAR, BOX[1] - 0.42, 0.0]},
        "ernst": {"pose": [REAR, BOX[1] + 0.42, 0.0]},
    }
    server, robots = await robots_in(world, settings)
    path = Path.relative(BOX, [(1.5, 0.0), (2.6, 0.8)])
    await together(
        {
            "elvis": lambda: pusher(robots["elvis"], path, object_id="victim", timeout=40.0),
            "ernst": lambda: steerer(robots["ernst"], path, 0.42, object_id="victim", timeout=40.0),
        },
        robots,
    )
    x, y, th = world.box_pose("victim")
    print(f"\ncurved path: box at ({x:.2f}, {y:.2f}, {th:.3f}), path ends at (7.1, 3.8)")
    await server.door.aclose()
    assert math.dist((x, y), (BOX[0] + 2.6, BOX[1] + 0.8)) < 0.6


async def test_one_robot_alone_does_not_translate_the_box(demo: WorldSpec) -> None:
    world = World(demo, seed=1)
    server, robots = await robots_in(world, {"elvis": {"pose": [REAR, BOX[1] - 0.42, 0.0]}})
    path = Path.relative(BOX, [(3.0, 0.0)])
    result = await pusher(robots["elvis"], path, object_id="victim", timeout=15.0)
    x, y, th = world.box_pose("victim")
    print(
        f"\npusher alone: box at ({x:.2f}, {y:.2f}, {th:.3f}) after 15 s, "
        f"{along(world, path):.2f} m along the path; {result}"
    )
    await server.door.aclose()
    assert along(world, path) < 0.5  # two robots go 3 m in ~10 s; alone it only pivots
    assert not result["done"]
