"""What a world process answers a viewer (``view.scene``, ``view.frame``), over a stand-in node."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from sim_hw import World, WorldServer, load_world
from sim_hw.grid.cli import build_server
from sim_hw.view import FRAME, SCENE, export_scene

WORLDS = Path(__file__).parents[3] / "worlds"


class _Node:
    def __init__(self) -> None:
        self.exported: dict[str, Callable[..., Any]] = {}

    def export(self, fn: Callable[..., Any], name: str | None = None) -> None:
        self.exported[name or fn.__name__] = fn


def test_the_pymunk_world_answers_its_recording_header() -> None:
    world = World(load_world(WORLDS / "search_and_rescue.toml"), seed=1)
    node = _Node()
    export_scene(node, WorldServer(world).door)
    assert set(node.exported) == {SCENE}
    scene = node.exported[SCENE]()
    assert scene["kind"] == "continuous"
    assert scene["size"] == [9.0, 6.0]
    assert {i["id"]: i["shape"] for i in scene["immovables"]} == {"pillar": "box", "rock": "circle"}
    assert scene["radii"]["ernst"] == 0.15 and scene["radii"]["*"] == 0.15


def test_a_grid_world_answers_its_cells_and_its_state(tmp_path: Path) -> None:
    grid = tmp_path / "g.txt"
    grid.write_text("#####\n#B.R#\n#...#\n#####\n")
    server = build_server(str(grid), {})
    node = _Node()
    export_scene(node, server.door)
    assert set(node.exported) == {SCENE, FRAME}
    scene = node.exported[SCENE]()
    assert scene["kind"] == "grid" and scene["shape"] == [4, 5]
    assert scene["obstacles"][1] == "#...#" and scene["base"] == [1, 1]
    frame = node.exported[FRAME]()
    assert frame["tick"] == 0 and frame["robots"] == {}
    assert len(frame["marks"]) == 20 and frame["resources"][8] > 0  # the R at row 1, column 3
