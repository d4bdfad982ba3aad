"""Two robot processes on a grid world process: join, idle rounds, a short foraging run."""

from __future__ import annotations

import asyncio
from pathlib import Path

import numpy as np
import pytest

from mover import Node, launch
from tests.helpers.procs import cluster
from tests.programs._grid import WORLD, start_robots, start_world, write_grid

pytestmark = pytest.mark.processes


async def test_two_robots_join_tick_and_forage(tmp_path: Path) -> None:
    obstacles = np.zeros((6, 6), dtype=bool)
    path = write_grid(tmp_path / "small.json", obstacles, (2, 2), {(4, 4): 150})
    names = ["a", "b"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, path, "--expect", "2")
        await start_robots(c, names, [{"view": 0}, {"view": 0}])
        await node.membership.wait_for([WORLD, *names], timeout=20)
        async with asyncio.timeout(10):
            while (idle := await node.call(WORLD, "state", timeout=5))["idle"] != names:
                await asyncio.sleep(0.05)
        assert sorted(idle["robots"]) == names
        await asyncio.sleep(0.3)
        still = await node.call(WORLD, "state", timeout=5)
        assert still["round"] == idle["round"], "idle robots hold the world still"
        pose = await node.call("a", "robot.pose", timeout=5)
        assert pose == [0.0, 0.0, 0.0]
        outcomes = await asyncio.wait_for(
            launch(node, "foraging", names, {"method": "cmarking", "seed": 1}, run="smoke"), 60
        )
        results = {n: o["result"] for n, o in outcomes.items()}
        assert all(r["finished"] for r in results.values()), outcomes
        assert len({r["rounds"] for r in results.values()}) == 1, "one round count for all"
        state = await node.call(WORLD, "state", timeout=5)
        assert state["remaining"] == 0 and state["dropped"] == []
        print(f"smoke: {results}")
