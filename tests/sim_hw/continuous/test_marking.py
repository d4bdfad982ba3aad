"""Targets a robot can mark (``MarkerSpec.hears``): the LED's ``mark:<id>`` message within
range marks one, cameras then read it ``marked``; and ``free_points`` for placing things."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sim_hw import (
    CameraSpec,
    MarkerSpec,
    ObstacleSpec,
    RobotSpec,
    World,
    WorldSpec,
    free_points,
    load_world,
    random_obstacles,
)

ROBOT = RobotSpec(camera=CameraSpec(max_range=3.0, fov=2 * math.pi))


def world() -> World:
    spec = WorldSpec(
        size=(6.0, 6.0),
        robot=ROBOT,
        markers=(
            MarkerSpec("target", "near", (2.0, 1.0), hears=1.0),
            MarkerSpec("target", "far", (3.9, 1.0), hears=1.0),
            MarkerSpec("target", "deaf", (1.0, 1.8)),
        ),
    )
    w = World(spec, seed=0)
    w.add_robot("r", RobotSpec(pose=(1.2, 1.0, 0.0), camera=ROBOT.camera))
    return w


def statuses(w: World) -> dict[str, str]:
    return {s[1]: s[2] for s in w.readings("r")["cam"] or ()}


def test_a_mark_message_within_range_marks_the_target() -> None:
    w = world()
    assert statuses(w) == {"near": "", "deaf": "", "far": ""}
    w.set_command("r", {"led": "mark:far"})  # 2.7 m away: seen, not heard
    w.step()
    w.set_command("r", {"led": "mark:deaf"})  # cannot be marked
    w.step()
    w.set_command("r", {"led": "mark:nothing"})
    w.step()
    assert w.marked == {}
    w.set_command("r", {"led": "mark:near"})
    w.step()
    assert w.marked == {"near": pytest.approx(0.4)}
    assert statuses(w)["near"] == "marked" and statuses(w)["far"] == ""
    w.step()  # a second message changes nothing
    assert w.marked == {"near": pytest.approx(0.4)}
    assert w.snapshot()["marked"] == w.marked


def test_hears_comes_from_the_world_file(tmp_path: Path) -> None:
    path = tmp_path / "w.toml"
    path.write_text(
        '[world]\nsize = [5.0, 5.0]\n[[targets]]\nid = "t"\ncenter = [2.0, 2.0]\nhears = 1.2\n'
    )
    assert load_world(path).markers[0].hears == 1.2


def test_free_points_keep_clear_and_are_seeded() -> None:
    spec = random_obstacles((10.0, 10.0), 10, np.random.default_rng(2), max_size=1.5)
    a = free_points(spec, 20, np.random.default_rng(5), clearance=0.4, apart=1.0)
    assert a == free_points(spec, 20, np.random.default_rng(5), clearance=0.4, apart=1.0)
    for x, y in a:
        assert 0.4 <= x <= 9.6 and 0.4 <= y <= 9.6
        for ob in spec.obstacles:
            r = ob.radius if ob.shape == "circle" else math.hypot(*ob.size) / 2
            assert math.dist((x, y), ob.center) >= r + 0.4
    assert min(math.dist(p, q) for p in a for q in a if p != q) >= 1.0
    avoid = free_points(spec, 3, np.random.default_rng(6), apart=2.0, avoid=tuple(a[:2]))
    assert all(math.dist(p, q) >= 2.0 for p in avoid for q in a[:2])


def test_free_points_refuse_a_full_arena() -> None:
    full = WorldSpec(size=(2.0, 2.0), obstacles=(ObstacleSpec("circle", (1.0, 1.0), radius=1.0),))
    with pytest.raises(ValueError, match="could place only 0 of 1"):
        free_points(full, 1, np.random.default_rng(0))
