"""The batched sensing reads what the per-robot queries read, bit for bit: the sonar
(``sim_hw.continuous._sonar``) what a query per ray read, the bumper (``_devices.Contacts``) what
each robot's ``Body.each_arbiter`` read."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymunk
import pytest

from sim_hw import BoxSpec, ObstacleSpec, RobotSpec, SonarSpec, World, WorldSpec
from sim_hw.continuous import _devices, _sonar, _world
from sim_hw.continuous._bodies import CAT_QUERY, SOLID


def slow_ranges(world: World, robot_id: str) -> list[float]:
    """The sonar as it was read before the batch: one ``segment_query_first`` per ray, noise
    drawn per hit (the robot's generator as it stood before the tick's sonar draws)."""
    robot = world.robots[robot_id]
    x, y, heading = world.pose(robot_id)
    spec = robot.parts.spec
    assert spec.sonar is not None
    sonar, radius = spec.sonar, spec.radius
    query = pymunk.ShapeFilter(group=robot.group, categories=CAT_QUERY, mask=SOLID)
    out = []
    for a in sonar.angles():
        c, s = math.cos(heading + a), math.sin(heading + a)
        start = (x + c * radius, y + s * radius)
        end = (x + c * (radius + sonar.max_range), y + s * (radius + sonar.max_range))
        hit = world.space.segment_query_first(start, end, 0.0, query)
        if hit is None:
            out.append(sonar.max_range)
            continue
        r = hit.alpha * sonar.max_range
        if sonar.noise > 0.0:
            r = min(max(r + float(robot.rng.normal(0.0, sonar.noise)), 0.0), sonar.max_range)
        out.append(r)
    return out


def _scene(seed: int, noise: float) -> World:
    """A crowd of robots of three sizes and ray counts (some overlapping at the start) among
    a box, a pushable crate, a post and a rail."""
    rng = np.random.default_rng(seed)
    obstacles = (
        ObstacleSpec("box", center=(4.0, 4.0), size=(1.0, 0.5), angle=0.3),
        ObstacleSpec("circle", center=(2.0, 6.0), radius=0.4),
        ObstacleSpec("segment", a=(6.0, 1.0), b=(7.0, 3.0), radius=0.05),
    )
    crate = BoxSpec(id="crate", center=(5.5, 6.0), size=(0.6, 0.6), mass=5.0)
    world = World(WorldSpec(size=(8.0, 8.0), obstacles=obstacles, boxes=(crate,)), seed=seed)
    for i in range(90):
        pose = (
            float(rng.uniform(0.3, 7.7)),
            float(rng.uniform(0.3, 7.7)),
            float(rng.uniform(-3, 3)),
        )
        sonar = SonarSpec(
            rays=int(rng.choice([8, 5, 12])), max_range=float(rng.choice([3.0, 1.5])), noise=noise
        )
        radius = float(rng.choice([0.15, 0.1, 0.2]))
        world.add_robot(f"r{i:02d}", RobotSpec(pose=pose, radius=radius, sonar=sonar))
    for robot in world.robots.values():
        robot.v, robot.w = 0.3, 0.5
    return world


@pytest.mark.parametrize("far", ["queries", "numpy"])
@pytest.mark.parametrize("noise", [0.0, 0.02])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_batch_reads_what_a_query_per_ray_read(
    seed: int, noise: float, far: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_world, "BATCH_FROM", 1)  # every tick batched, whatever the crowd
    # the rays open past NEAR: each asked of chipmunk, or numpy over the discs in reach
    monkeypatch.setattr(_sonar, "PAIRS_PER_QUERY", 0.0 if far == "queries" else math.inf)
    batched, slow = _scene(seed, noise), _scene(seed, noise)
    reference: dict[str, list[float]] = {}

    def measure_slowly(robots: list[_world._Robot]) -> None:
        for robot in robots:  # odometry first, then the sonar, as the world draws noise
            slow._odometry(robot, _world._pose(robot.parts.body))
            reference[robot.id] = slow_ranges(slow, robot.id)

    monkeypatch.setattr(slow, "_measure_all", measure_slowly)
    hits = 0
    for _ in range(3):
        batched.step()
        slow.step()
        for rid, robot in batched.robots.items():
            ranges = robot.readings["sonar"]
            assert ranges == reference[rid], rid
            hits += sum(r < batched.robots[rid].parts.spec.sonar.max_range for r in ranges)  # type: ignore[union-attr]
    assert hits > 500  # the scene is a crowd: most rays hit something


def slow_bumper(body: pymunk.Body) -> str | None:
    """The bumper as it was read before the batch: the body's own arbiters, one at a time."""
    bearings: list[float] = []

    def visit(arb: pymunk.Arbiter) -> None:
        n = arb.normal
        sign = 1.0 if arb.bodies[0] is body else -1.0
        bearings.append(_devices.wrap(math.atan2(sign * n.y, sign * n.x) - body.angle))

    body.each_arbiter(visit)
    if not bearings:
        return None
    bearing = min(bearings, key=abs)
    if abs(bearing) <= math.pi / 4:
        return "front"
    if abs(bearing) >= 3 * math.pi / 4:
        return "back"
    return "left" if bearing > 0 else "right"


@pytest.mark.parametrize("batched", [False, True])
def test_the_bumper_reads_what_each_robots_arbiters_read(
    batched: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if batched:
        monkeypatch.setattr(_world, "BATCH_FROM", 1)
    world = _scene(4, 0.0)
    rng = np.random.default_rng(4)
    sides: dict[str | None, int] = {}
    for _ in range(40):
        for robot in world.robots.values():  # turning at random: contacts begin and end
            robot.v, robot.w = 0.4, float(rng.uniform(-3.0, 3.0))
        world.step()
        for rid, robot in world.robots.items():
            side = robot.readings["bump"]
            assert side == slow_bumper(robot.parts.body), rid
            sides[side] = sides.get(side, 0) + 1
    assert set(sides) == {None, "front", "left", "right", "back"}  # every side was read
    assert sum(v for k, v in sides.items() if k) > 500  # a crowd: many contacts


def test_batched_readings_are_a_robot_at_a_time_readings(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every field of every robot's readings, the floor under it included (cells written with
    and without a colour), tick after tick: the batch against a robot at a time."""
    runs = []
    for batch_from in (1, 10**9):
        monkeypatch.setattr(_world, "BATCH_FROM", batch_from)
        world = _scene(5, 0.02)
        rng = np.random.default_rng(5)
        for i in range(world.floor.shape[0]):
            world.floor.set(i, i % world.floor.shape[1], i, "red" if i % 2 else "")
        readings = []
        for tick in range(12):
            for rid in sorted(world.robots):
                command: dict[str, Any] = {
                    "v": float(rng.uniform(0, 0.5)),
                    "w": float(rng.uniform(-3, 3)),
                }
                if tick % 3 == 0:
                    command["floor"] = [tick, "blue" if tick % 2 else ""]
                world.set_command(rid, command)
            world.step()
            readings.append({rid: r.readings for rid, r in world.robots.items()})
        runs.append(readings)
    assert runs[0] == runs[1]
    floors = {tuple(r["floor"]) for tick in runs[0] for r in tick.values()}
    assert {c for _, c in floors} == {"", "red", "blue"}  # every kind of cell was read
