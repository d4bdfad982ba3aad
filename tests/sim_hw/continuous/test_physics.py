"""Bounded force: whether a box needs one robot or two is physics, not a flag."""

from __future__ import annotations

import pytest

from sim_hw import BoxSpec, ImmovableSpec, RobotSpec, World, WorldSpec
from sim_hw.continuous._bodies import GRAVITY

from .conftest import start

BOX = BoxSpec("big", center=(5.0, 4.0), size=(0.6, 0.6), mass=20.0, friction=0.5)
FORCE = 70.0


def test_margins_are_at_least_15_percent() -> None:
    slide = BOX.friction * BOX.mass * GRAVITY  # 98.1 N
    assert 0.85 * slide >= FORCE
    assert 1.15 * slide <= 2 * FORCE


def _push_with(n: int, seconds: float = 5.0) -> float:
    world = World(WorldSpec(size=(10.0, 8.0), boxes=(BOX,)))
    rim = BOX.center[0] - BOX.size[0] / 2 - 0.15 - 0.002
    offsets = [0.0] if n == 1 else [-0.155, 0.155]
    for k, dy in enumerate(offsets):
        world.add_robot(f"r{k}", RobotSpec(pose=(rim, BOX.center[1] + dy, 0.0), force=FORCE))
        world.set_command(f"r{k}", {"v": 0.3, "w": 0.0})
    for _ in range(round(seconds / 0.1)):
        world.step()
    x, y, _ = world.box_pose("big")
    return float(((x - BOX.center[0]) ** 2 + (y - BOX.center[1]) ** 2) ** 0.5)


def test_one_robot_cannot_translate_the_box() -> None:
    assert _push_with(1) < 0.01


def test_two_robots_can() -> None:
    assert _push_with(2) > 1.0


@pytest.mark.parametrize(
    ("thing", "moved"),
    [
        (BoxSpec("light", center=(5.0, 4.0), size=(0.4, 0.4), mass=5.0), True),
        (BOX, False),
        (ImmovableSpec("pillar", center=(5.0, 4.0), size=(0.4, 0.4)), False),
    ],
)
async def test_push_sense_tells_movable_from_not(
    thing: BoxSpec | ImmovableSpec, moved: bool
) -> None:
    boxes = (thing,) if isinstance(thing, BoxSpec) else ()
    immovables = (thing,) if isinstance(thing, ImmovableSpec) else ()
    world = World(WorldSpec(size=(10.0, 8.0), boxes=boxes, immovables=immovables))
    x = 5.0 - thing.size[0] / 2 - 0.15 - 0.05
    server, hws = await start(world, {"r": {"pose": [x, 4.0, 0.0]}})
    assert hws["r"].push is not None
    result = await hws["r"].push.push(force=50.0, duration=2.0)
    assert result.object_id == thing.id
    assert result.moved is moved
    await server.door.aclose()


async def test_push_with_nothing_ahead_reports_nothing() -> None:
    world = World(WorldSpec(size=(10.0, 8.0)))
    server, hws = await start(world, {"r": {"pose": [2.0, 4.0, 0.0]}})
    assert hws["r"].push is not None
    result = await hws["r"].push.push(force=50.0, duration=0.5)
    assert result.object_id is None
    assert not result.moved
    await server.door.aclose()


def test_pusher_and_steerer_turn_the_box_together() -> None:
    # Brown & Jennings' pusher/steerer: robots at the two rear corners; the steerer (left
    # corner) goes slower than the pusher, so the box turns towards the steerer's side.
    world = World(WorldSpec(size=(12.0, 10.0), boxes=(BOX,)))
    rim = BOX.center[0] - BOX.size[0] / 2 - 0.15 - 0.002
    world.add_robot("pusher", RobotSpec(pose=(rim, BOX.center[1] - 0.2, 0.0)))
    world.add_robot("steerer", RobotSpec(pose=(rim, BOX.center[1] + 0.2, 0.0)))
    for _ in range(30):
        world.set_command("pusher", {"v": 0.3, "w": 0.0})
        world.set_command("steerer", {"v": 0.15, "w": 0.0})
        world.step()
    x, _, angle = world.box_pose("big")
    assert x - BOX.center[0] > 0.2  # it slid forward ...
    assert angle > 0.1  # ... and turned left, towards the slower steerer
