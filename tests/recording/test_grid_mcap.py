"""A grid world's run recorded as MCAP reads back, with rosbags and with mover's reader, as the
world's own snapshots: the cells and the floor values as ``nav_msgs/OccupancyGrid`` each round,
the robots at their cells' centres, stamps one second a round."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")
pytest.importorskip("rosbags", reason="needs rosbags (the test extra)")

from sim_hw import read_recording
from sim_hw.grid import Grid, GridServer, GridWorld
from sim_hw.grid._mcap import GridMcapSink
from sim_hw.view._scene import grid_state
from tests.recording._rosbags import by_topic

ROOT = Path(__file__).resolve().parents[2]
EAST, WEST = 1, 3
# a robot's action each round: a writes a value it then walks off, b walks west
ACTIONS = [
    ({"move": EAST, "value": 7}, {"move": WEST}),
    ({"move": EAST, "value": 250}, {"move": WEST, "value": 3}),
    ({"move": EAST}, {}),
]


def _server() -> GridServer:
    rows = [[1] * 7, [1, 0, 0, 0, 0, 0, 1], [1, 0, 1, 1, 1, 0, 1], [1] * 7]
    return GridServer(GridWorld(Grid(np.array(rows)), (1, 1)), exclusive=True, expect=2)


async def _run(path: Path) -> list[dict[str, Any]]:
    """Three rounds of two robots, recorded; the world's own frame after each round."""
    server = _server()
    sink = GridMcapSink(path, server, seed=11)
    server.door.on_tick.append(sink)
    frames: list[dict[str, Any]] = []
    try:
        await asyncio.gather(
            server.door.join("a", {"start": [1, 1]}), server.door.join("b", {"start": [1, 5]})
        )
        frames.append(grid_state(server.stepper))
        for k, (act_a, act_b) in enumerate(ACTIONS):
            await asyncio.gather(server.door.step("a", k, act_a), server.door.step("b", k, act_b))
            frames.append(grid_state(server.stepper))
    finally:
        sink.close()
    return frames


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[dict[str, Any]]]:
    path = tmp_path_factory.mktemp("grid") / "grid.mcap"
    return path, asyncio.run(_run(path))


def test_rosbags_reads_occupancy_grids_of_the_cells_and_floor_each_round(
    run: tuple[Path, list[dict[str, Any]]],
) -> None:
    path, frames = run
    got = by_topic(path)
    # round 0 is written when the recording starts, before the robots join
    cells = got["/grid/cells"]
    assert {kind for _, kind, _ in cells} == {"nav_msgs/msg/OccupancyGrid"}
    assert [t for t, _, _ in cells] == [k * 1_000_000_000 for k in range(len(ACTIONS) + 1)]
    grid = cells[0][2]
    assert (grid.info.width, grid.info.height, grid.info.resolution) == (7, 4, 1.0)
    obstacles = _server().grid.obstacles.ravel()
    assert grid.data.tolist() == [100 if o else 0 for o in obstacles]
    floors = [m for _, _, m in got["/grid/floor"]]
    assert len(floors) == len(ACTIONS) + 1
    for msg, frame in zip(floors[1:], frames[1:], strict=True):
        want = [-1 if v < 0 else min(v, 100) for v in frame["marks"]]
        assert msg.data.tolist() == want
    assert 250 in frames[-1]["marks"] and 100 in floors[-1].data.tolist()  # clipped
    assert msg.header.stamp.sec == len(ACTIONS) and msg.header.frame_id == "world"
    for rid in ("a", "b"):
        poses = got[f"/{rid}/pose"]
        assert {kind for _, kind, _ in poses} == {"geometry_msgs/msg/PoseStamped"}
        r, c = frames[-1]["robots"][rid]
        last = poses[-1][2].pose.position
        assert (last.x, last.y) == (c + 0.5, r + 0.5)
    assert [tr.child_frame_id for tr in got["/tf"][-1][2].transforms] == ["a", "b"]


def test_mover_reads_back_the_frames_and_the_seed(run: tuple[Path, list[dict[str, Any]]]) -> None:
    path, frames = run
    header, ticks = read_recording(path)
    assert header["kind"] == "grid" and header["seed"] == 11 and header["shape"] == [4, 7]
    assert [t["tick"] for t in ticks] == list(range(len(ACTIONS) + 1))
    for tick, frame in zip(ticks[1:], frames[1:], strict=True):
        assert {k: tick[k] for k in frame} == frame and tick["t"] == float(tick["tick"])


@pytest.mark.processes
def test_a_grid_recording_is_not_a_png_nor_exported_again(
    run: tuple[Path, list[dict[str, Any]]], tmp_path: Path
) -> None:
    path, _ = run
    for out, says in (("x.png", "plays in the viewer only"), ("x.mcap", "is MCAP already")):
        done = subprocess.run(
            [sys.executable, "-m", "mover", "replay", str(path), "--out", str(tmp_path / out)],
            capture_output=True,
            text=True,
            timeout=60,
            cwd=ROOT,
        )
        assert done.returncode == 2 and says in done.stderr, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1


def test_a_grid_records_as_mcap_only(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    from mover.cli._main import main

    path = str(ROOT / "teams" / "foraging_field.txt")  # the grid of docs/recordings.md
    assert main(["gridworld", path, "--record", str(tmp_path / "grid.jsonl")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"mover gridworld: --record: a grid run records as .mcap, got '{tmp_path / 'grid.jsonl'}'"
    ]
