"""World files load, generators are seeded, and bad files get precise messages."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mover import ConfigError
from sim_hw import World, WorldFileError, double_corridor, load_world, random_obstacles

WORLDS = sorted((Path(__file__).parents[3] / "worlds").glob("*.[tj]*"))


@pytest.mark.parametrize("path", WORLDS, ids=lambda p: p.name)
def test_example_worlds_load_and_run(path: Path) -> None:
    spec = load_world(path)
    world = World(spec, seed=1)
    for rid in list(spec.robots) or ["r0", "r1"]:
        world.add_robot(rid)
        world.set_command(rid, {"v": 0.3, "w": 0.2})
    for _ in range(10):
        world.step()
    assert world.time == pytest.approx(1.0)


def test_search_and_rescue_file_fields() -> None:
    spec = load_world(Path(__file__).parents[3] / "worlds" / "search_and_rescue.toml")
    assert spec.size == (9.0, 6.0)
    assert spec.robots["moseley"].pose == (0.8, 5.0, 0.0)
    sonar, camera = spec.robots["ernst"].sonar, spec.robot.camera
    assert sonar is not None and sonar.noise == 0.01
    assert camera is not None and camera.fov == pytest.approx(math.radians(120))
    victim = next(b for b in spec.boxes if b.id == "victim")
    assert (victim.mass, victim.friction) == (20.0, 0.5)


def test_generators_are_seeded() -> None:
    a = random_obstacles((10.0, 10.0), 12, np.random.default_rng(3))
    b = random_obstacles((10.0, 10.0), 12, np.random.default_rng(3))
    c = random_obstacles((10.0, 10.0), 12, np.random.default_rng(4))
    assert a == b != c
    assert len(a.obstacles) == 12


def test_double_corridor_lengths() -> None:
    even, longer = double_corridor(length=10.0, ratio=1.0), double_corridor(length=10.0, ratio=2.0)
    assert longer.size[0] - even.size[0] == pytest.approx(5.0)  # a 2·5 m sideways detour
    assert {m.id for m in even.markers} == {"source", "target"}


BAD = [
    # (file, text, line (None: the file as a whole or no line known), what the error says)
    (
        "world.toml",
        "[world]\nsize = [10, 'x']\n",
        2,
        "world.size: must be a list of 2 numbers, got [10, 'x']",
    ),
    (
        "boxes.toml",
        "[world]\nsize = [10, 10]\n[[boxes]]\nid='a'\ncenter=[1,1]\nsize=[1,1]\n"
        "mass=2\n[[boxes]]\nid='b'\ncenter=[2,2]\nsize=[1,1]\nmass=-1\n",
        12,
        "boxes[1].mass: must be > 0 and at most 1000000, got -1",
    ),
    (
        "typo.toml",
        "[world]\nsize = [10, 10]\n[robot]\nradious = 0.2\n",
        4,
        "robot.radious: unknown key (did you mean 'radius'?); known: pose, radius, mass,",
    ),
    ("syntax.toml", "[world]\nsize = [10, 10\n", None, "not valid TOML"),
    ("badkey.toml", "[world]\nsize = [10, 10]\n= 3\n", 3, "not valid TOML"),
    (
        "syntax.json",
        '{"world": {"size": [10, 10]},\n "boxes": [}\n',
        2,
        "not valid JSON: Expecting value (column 12)",
    ),
    (
        "dup.toml",
        "[world]\nsize=[5,5]\n[[targets]]\nid='t'\ncenter=[1,1]\n[[beacons]]\n"
        "id='t'\ncenter=[2,2]\n",
        7,
        "beacons[0].id: 't' is already used in targets",
    ),
    (
        "shape.toml",
        "[world]\nsize=[5,5]\n[[obstacles]]\nshape='triangle'\n",
        4,
        "obstacles[0].shape: must be 'box', 'circle' or 'segment', got 'triangle'",
    ),
    (
        "outside.toml",
        "[world]\nsize=[5,5]\n[[robots]]\nid='r'\npose=[6,1,0]\n",
        5,
        "robots[0].pose: (6.0, 1.0) is outside the arena",
    ),
    (
        "gen.toml",
        "[generator]\nkind='maze'\n",
        2,
        "generator.kind: must be 'random_obstacles' or 'double_corridor', got 'maze'",
    ),
    ("noworld.toml", "[[boxes]]\nid='a'\n", None, "world: is required (a table with"),
    (
        "sonar.toml",
        "[world]\nsize=[5,5]\n[robot]\nsonar={rays=0}\n",
        4,
        "robot.sonar.rays: must be from 1 to 360, got 0",
    ),
    (
        "many.json",
        '{"world": {"size": [5, 5]}, "eyebots": [' + ", ".join(["{}"] * 1001) + "]}",
        None,
        "eyebots: must hold at most 1000 tables, got 1001",
    ),
    ("world.yaml", "world: {}\n", None, "must end in .toml or .json"),
]


@pytest.mark.parametrize(("name", "text", "line", "message"), BAD, ids=[b[0] for b in BAD])
def test_bad_files_are_rejected_precisely(
    tmp_path: Path, name: str, text: str, line: int | None, message: str
) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(WorldFileError) as info:
        load_world(path)
    text = str(info.value)
    assert text.startswith(f"{path}: " if line is None else f"{path}:{line}: "), text
    assert message in text, text
    assert info.value.line == line
    assert isinstance(info.value, ValueError) and isinstance(info.value, ConfigError)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(WorldFileError, match="cannot read"):
        load_world(tmp_path / "nope.toml")
