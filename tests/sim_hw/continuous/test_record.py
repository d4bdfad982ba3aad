"""Recording a run, drawing it with ``mover replay``, and the CLI's errors."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mover._cli import main
from sim_hw import (
    Recorder,
    World,
    WorldServer,
    in_process,
    load_world,
    read_recording,
)
from sim_hw.continuous._walker import random_walk

WORLDS = Path(__file__).parents[3] / "worlds"


async def _record(path: Path) -> World:
    world = World(load_world(WORLDS / "search_and_rescue.toml"), seed=2)
    recorder = Recorder(path, world)
    snapshots: list[dict[str, Any]] = []
    server = WorldServer(world, expect=2, snapshot_every=5, on_snapshot=snapshots.append)
    server.door.on_tick.append(recorder)

    async def robot(rid: str, seed: int) -> None:
        hw = await in_process(server, rid)
        await random_walk(hw, np.random.default_rng(seed), 50)

    await asyncio.gather(robot("ernst", 1), robot("moseley", 2))
    await server.door.aclose()
    recorder.close()
    assert [s["tick"] for s in snapshots] == list(range(5, 51, 5))
    assert set(snapshots[0]["robots"]) == {"ernst", "moseley"}
    return world


async def test_recording_and_replay(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rec = tmp_path / "run.jsonl"
    await _record(rec)
    header, ticks = read_recording(rec)
    assert header["size"] == [9.0, 6.0]
    assert len(ticks) == 52  # the start, the walkers' first (stop) tick and 50 more
    assert ticks[-1]["robots"]["ernst"][:2] != ticks[1]["robots"]["ernst"][:2]
    assert set(ticks[1]["commands"]) == {"ernst", "moseley"}
    png = tmp_path / "run.png"
    assert main(["replay", str(rec), "--out", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_replay_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["replay", str(tmp_path / "none.jsonl"), "--out", "x.png"]) == 2
    assert "no such file" in capsys.readouterr().err
    junk = tmp_path / "junk.jsonl"
    junk.write_text('{"type": "tick"}\n')
    assert main(["replay", str(junk), "--out", str(tmp_path / "x.png")]) == 2
    ours = _our_lines(capsys.readouterr().err, "replay")
    assert len(ours) == 1
    assert "no header line" in ours[0]


def test_world_rejects_a_bad_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[world]\nsize = [10, -1]\n")
    assert main(["world", str(bad), "--lockstep"]) == 2
    ours = _our_lines(capsys.readouterr().err, "world")
    assert ours == [
        f"mover world: {bad}:2: world.size: must be a list of 2 numbers, each > 0 and at most "
        "1000, got [10, -1]"
    ]


def _our_lines(err: str, verb: str) -> list[str]:
    """The verb's own lines (other verbs may log that they failed to load)."""
    return [line for line in err.splitlines() if line.startswith(f"mover {verb}")]
