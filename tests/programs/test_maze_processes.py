"""A 4-robot-process CU-LVP maze run matches the in-process run of the same seed and maze."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from experiments.maze import run_trial
from mover import Node, launch
from sim_hw.grid import generate_maze, save_maze
from tests.helpers.procs import cluster
from tests.programs._grid import WORLD, start_robots, start_world

pytestmark = pytest.mark.processes

SEED = 2


async def test_distributed_maze_run_matches_the_in_process_run(tmp_path: Path) -> None:
    maze = generate_maze(20, 0.85, np.random.default_rng(SEED), n_starts=4)
    path = tmp_path / "maze.json"
    save_maze(path, maze)
    reference = run_trial(maze, 4, "cu-lvp", np.random.SeedSequence(SEED))
    assert reference["complete"]
    names = ["m0", "m1", "m2", "m3"]  # agent i is the i-th member in name order
    starts = [list(s) for s in maze.starts[:4]]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, path, "--expect", "4")
        await start_robots(c, names, [{"start": s, "view": 2} for s in starts])
        await node.membership.wait_for([WORLD, *names], timeout=20)
        t0 = time.monotonic()
        outcomes = await asyncio.wait_for(
            launch(
                node,
                "explore_maze",
                names,
                {
                    "method": "cu_lvp",
                    "seed": SEED,
                    "starts": starts,
                    "shape": list(maze.shape),
                    "snapshot_dir": str(tmp_path / "maps"),
                },
                run="maze",
            ),
            100,
        )
        took = time.monotonic() - t0
        results: dict[str, Any] = {n: o.get("result") for n, o in outcomes.items()}
        assert all(r and r["finished"] for r in results.values()), outcomes
        state = await node.call(WORLD, "state", timeout=5)
        assert state["explored"] == state["observable"] == reference["observable"]
    rounds = {r["rounds"] for r in results.values()}
    moves = sum(r["moves"] for r in results.values())
    sent = sum(r["sent_bytes"] for r in results.values())
    print(
        f"\nmaze 20 (p=0.85), 4 robots: in-process {reference['rounds']} rounds, cost "
        f"{reference['cost']}; distributed {rounds} rounds, cost {moves}, in {took:.1f} s; "
        f"messages {sent} B (in-process {reference['comm_sent_kB'] * 1000:.0f} B)"
    )
    assert rounds == {reference["rounds"]}
    assert moves == reference["cost"]
    assert sent == round(reference["comm_sent_kB"] * 1000)
    maps = sorted((tmp_path / "maps").glob("*.txt"))
    assert [m.stem for m in maps] == names
    print(maps[0].read_text())
