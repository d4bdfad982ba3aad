"""A robot process killed (or hung) mid-run does not hang the grid world or the others.

A hung process (SIGSTOP) is seen leaving the team when its zenoh lease (1 s) runs out, about
when the world's own --timeout (1 s here) would drop it; whichever comes first logs the drop.
"""

from __future__ import annotations

import asyncio
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from mover import Node, launch
from sim_hw.grid import place_resources, random_obstacles
from tests.helpers.procs import cluster
from tests.programs._grid import WORLD, start_robots, start_world, write_grid

pytestmark = pytest.mark.processes

BASE = (7, 7)
NAMES = ["k0", "k1", "k2", "k3"]


def field(tmp_path: Path) -> Path:
    grid = random_obstacles(15, 15, 0.05, 11, keep_free=(BASE,))
    resources = place_resources(grid, 2, 1000, 12, exclude=(BASE,), reachable_from=BASE)
    return write_grid(tmp_path / "field.json", grid.obstacles, BASE, resources)


async def _run_and_stop_one(tmp_path: Path, sig: signal.Signals, timeout: str) -> None:
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, field(tmp_path), "--expect", "4", "--timeout", timeout)
        procs = await start_robots(c, NAMES, [{"view": 0}] * 4)
        await node.membership.wait_for([WORLD, *NAMES], timeout=20)
        run = asyncio.ensure_future(launch(node, "foraging", NAMES, {"seed": 5}, run="kill"))
        async with asyncio.timeout(30):  # until the run is under way: the victim has moved
            while (await node.call(WORLD, "state", timeout=5))["moves"].get("k1", 0) < 5:
                await asyncio.sleep(0.05)
        stopped = time.monotonic()
        procs[1].send_signal(sig)
        async with asyncio.timeout(20):  # the world goes on without it
            while "k1" not in (state := await node.call(WORLD, "state", timeout=5))["dropped"]:
                await asyncio.sleep(0.05)
        dropped_after = time.monotonic() - stopped
        before = state["round"]
        await asyncio.sleep(0.3)
        after = await node.call(WORLD, "state", timeout=5)
        assert after["round"] > before, "the world is stuck"
        outcomes = await asyncio.wait_for(run, 90)
        survivors: dict[str, Any] = {n: outcomes[n].get("result") for n in NAMES if n != "k1"}
        assert all(r and r["finished"] for r in survivors.values()), outcomes
        assert "error" in outcomes["k1"]
        end = await node.call(WORLD, "state", timeout=5)
        assert end["remaining"] == 0 and sorted(end["robots"]) == ["k0", "k2", "k3"]
        print(
            f"\n{sig.name}: k1 dropped {dropped_after * 1000:.0f} ms after the signal; the "
            f"others finished in {survivors['k0']['rounds']} rounds"
        )


async def test_a_killed_robot_process_does_not_hang_the_grid_world(tmp_path: Path) -> None:
    await _run_and_stop_one(tmp_path, signal.SIGKILL, "5")


async def test_a_hung_robot_process_is_dropped_within_seconds(tmp_path: Path) -> None:
    await _run_and_stop_one(tmp_path, signal.SIGSTOP, "1")


async def test_maze_survivors_finish_without_a_killed_member(tmp_path: Path) -> None:
    import numpy as np

    from sim_hw.grid import generate_maze, save_maze

    maze = generate_maze(20, 0.85, np.random.default_rng(3), n_starts=4)
    save_maze(tmp_path / "maze.json", maze)
    names = ["m0", "m1", "m2", "m3"]
    starts = [list(s) for s in maze.starts[:4]]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, tmp_path / "maze.json", "--expect", "4")
        procs = await start_robots(c, names, [{"start": s} for s in starts])
        await node.membership.wait_for([WORLD, *names], timeout=20)
        run = asyncio.ensure_future(
            launch(
                node,
                "explore_maze",
                names,
                {"seed": 3, "starts": starts, "shape": list(maze.shape)},
                run="maze-kill",
            )
        )
        async with asyncio.timeout(30):
            while (await node.call(WORLD, "state", timeout=5))["moves"].get("m1", 0) < 5:
                await asyncio.sleep(0.02)
        procs[1].kill()
        outcomes = await asyncio.wait_for(run, 90)
        survivors: dict[str, Any] = {n: outcomes[n].get("result") for n in names if n != "m1"}
        assert all(r and r["finished"] for r in survivors.values()), outcomes
        state = await node.call(WORLD, "state", timeout=5)
        assert state["dropped"] == ["m1"] and state["explored"] == state["observable"]
        print(f"\nmaze without m1: finished in {survivors['m0']['rounds']} rounds")
