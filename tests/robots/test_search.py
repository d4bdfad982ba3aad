"""search and movable (section 4.1) in the simulated world, one robot, seeded."""

from __future__ import annotations

import math
import random

import pytest

from robots import Robot
from robots.library import (
    Predicate,
    Rect,
    Region,
    approach,
    kind_ahead,
    locate,
    movable,
    search,
    sees,
)
from sim_hw import BoxSpec, ImmovableSpec, World, WorldSpec

from .conftest import robots_in

SEED = 1  # a run that tests walls, the pillar and the 2-robot box before the crate


def spying(
    predicate: Predicate, log: list[tuple[str | None, bool]], by_id: bool = False
) -> Predicate:
    """The predicate, logging what the camera saw ahead at each check (its kind, or its id)
    and the verdict; "wall" stands for walls and static obstacles, which the camera omits."""

    async def spy(robot: Robot) -> bool:
        cam = robot.hw.camera
        sightings = cam.sightings() if cam is not None else ()
        what = (
            locate(robot.hw.odometry.pose(), sightings, 0.15)[0] if by_id else kind_ahead(sightings)
        )
        verdict = await predicate(robot)
        log.append((what or "wall", verdict))
        return verdict

    return spy


@pytest.mark.parametrize(("robot_id", "seed"), [("ernst", 0), ("elvis", 5), ("moseley", 7)])
async def test_search_finds_the_box_and_ignores_walls_and_immovables(
    demo: WorldSpec, robot_id: str, seed: int
) -> None:
    world = World(demo, seed=seed)
    server, robots = await robots_in(world, {robot_id: None})
    robot = robots[robot_id]
    checks: list[tuple[str | None, bool]] = []
    found = await search(
        robot,
        spying(sees("box"), checks),
        rng=random.Random(seed),
        terminator=lambda: robot.hw.clock.now() > 600,
    )
    print(f"\nsearch ({robot_id}, seed {seed}): {robot.hw.clock.now():.1f} s, checks {checks}")
    await server.door.aclose()
    assert found is not None and found.object_id == "victim"
    assert math.dist(found.location, world.box_pose("victim")[:2]) < 0.15
    assert checks[-1] == ("box", True)
    rejected = {kind for kind, ok in checks if not ok}
    assert rejected == {"wall", "immovable"}  # it bumped, tested and left other things first
    assert all(ok == (kind == "box") for kind, ok in checks)


async def test_search_gives_up_when_the_terminator_says_so(demo: WorldSpec) -> None:
    server, robots = await robots_in(World(demo), {"elvis": None})
    robot = robots["elvis"]

    async def never(_: Robot) -> bool:
        return False

    assert (
        await search(robot, never, lambda: robot.hw.clock.now() > 20.0, rng=random.Random(0))
        is None
    )
    await server.door.aclose()


# The paper's push test on things placed in front of the robot: a crate one robot can move,
# a wall, an immovable pillar, and the demo's 2-robot box (which one robot cannot move).
PUSHED = WorldSpec(
    size=(8.0, 8.0),
    boxes=(
        BoxSpec("crate", (2.0, 2.0), (0.4, 0.4), 5.0, 0.5),
        BoxSpec("victim", (2.0, 6.0), (0.6, 1.2), 20.0, 0.5),
    ),
    immovables=(ImmovableSpec("pillar", (6.0, 2.0), size=(0.6, 0.6)),),
)


@pytest.mark.parametrize(
    ("target", "expected"),
    [
        ((2.0, 2.0), True),  # the crate
        ((6.0, 2.0), False),  # the pillar
        ((7.8, 5.0), False),  # the east wall
        ((2.0, 6.0), False),  # the 2-robot box: one robot cannot move it, even off-centre
    ],
)
async def test_movable_is_the_push_test(target: tuple[float, float], expected: bool) -> None:
    x0, y0 = target[0] - 1.2, target[1] + 0.12  # a little off-centre
    server, robots = await robots_in(World(PUSHED), {"r": {"pose": [x0, y0, 0.0]}})
    robot = robots["r"]
    assert await approach(robot, 0.0, limit=1.5)
    assert await movable(robot) is expected
    assert robot.hw.clock.now() < 30
    await server.door.aclose()


@pytest.mark.parametrize("seed", [SEED])
async def test_search_with_the_push_test_finds_the_crate(seed: int) -> None:
    """The paper's own recognition end to end: the crate gives under one robot's medium push;
    walls, the pillar and the 2-robot box do not."""
    small = WorldSpec(
        size=(5.0, 5.0),
        boxes=(
            BoxSpec("crate", (1.0, 4.0), (0.4, 0.4), 5.0),
            BoxSpec("victim", (3.5, 3.5), (0.6, 1.2), 20.0),
        ),
        immovables=(ImmovableSpec("pillar", (4.0, 1.0), size=(0.6, 0.6)),),
    )
    world = World(small, seed=seed)
    server, robots = await robots_in(world, {"r": {"pose": [2.0, 2.0, 0.0]}})
    robot = robots["r"]
    checks: list[tuple[str | None, bool]] = []
    found = await search(
        robot,
        spying(movable, checks, by_id=True),
        rng=random.Random(seed),
        terminator=lambda: robot.hw.clock.now() > 900,
    )
    print(f"\nsearch by push: {robot.hw.clock.now():.1f} s, checks {checks}")
    await server.door.aclose()
    assert found is not None and found.object_id == "crate"
    assert checks[-1] == ("crate", True)
    assert all(not ok for _, ok in checks[:-1])
    assert {"victim", "pillar", "wall"} <= {what for what, _ in checks}


# Two crates in opposite quadrants of a square arena, the robot between them at the centre.
QUADRANTS = WorldSpec(
    size=(6.0, 6.0),
    boxes=(
        BoxSpec("south_west", (1.5, 1.5), (0.4, 0.4), 5.0),
        BoxSpec("north_east", (4.5, 4.5), (0.4, 0.4), 5.0),
    ),
)


ARENA = Rect(0.0, 0.0, 6.0, 6.0)


def north_west(p: tuple[float, float]) -> bool:
    """A region given as a plain predicate on positions (no centre to aim at)."""
    return p[0] <= 3.0 and p[1] >= 3.0


@pytest.mark.parametrize(
    ("region", "crate"),
    [(ARENA.split()[0], "south_west"), (ARENA.split()[3], "north_east"), (north_west, None)],
    ids=["quadrant-sw", "quadrant-ne", "predicate-nw"],
)
async def test_a_search_limited_to_a_quadrant_stays_there_and_finds_only_its_crate(
    region: Region, crate: str | None
) -> None:
    world = World(QUADRANTS, seed=2)
    server, robots = await robots_in(world, {"r": {"pose": [3.0, 3.0, 0.0]}})
    robot = robots["r"]
    path: list[tuple[float, float]] = []
    tested: list[str | None] = []

    def give_up() -> bool:
        path.append(robot.hw.odometry.pose()[:2])
        return robot.hw.clock.now() > 300

    async def spy(robot: Robot) -> bool:
        tested.append(kind_ahead(robot.hw.camera.sightings() if robot.hw.camera else ()))
        return await sees("box")(robot)

    found = await search(robot, spy, give_up, random.Random(2), region=region)
    print(f"\n{crate}: {robot.hw.clock.now():.1f} s, tested {tested}")
    await server.door.aclose()
    assert (found and found.object_id) == crate
    assert "box" not in tested[:-1] and (crate is not None or "box" not in tested)
    # it starts on the corner of all four; once well inside its quadrant, it stays near
    box = region if isinstance(region, Rect) else ARENA.split()[2]
    x0, y0, x1, y1 = box.x_min, box.y_min, box.x_max, box.y_max
    deep = Rect(x0 + 0.3, y0 + 0.3, x1 - 0.3, y1 - 0.3)
    wide = Rect(x0 - 0.4, y0 - 0.4, x1 + 0.4, y1 + 0.4)  # a turn's worth
    after = path[[deep(p) for p in path].index(True) :]
    print(f"{sum(map(region, after))} of {len(after)} ticks in, the rest within 0.4 m")
    assert all(wide(p) for p in after)
    assert sum(map(region, after)) > 0.85 * len(after)
