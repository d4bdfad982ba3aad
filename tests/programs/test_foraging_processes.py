"""Four robot processes forage a 12x12 grid on a grid world process, to completion; with
sequential turns, in exactly the iterations of the in-process runner."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from experiments.foraging import Setup, run_trial
from mover import BadArguments, Node, launch
from sim_hw.grid import place_resources, random_obstacles
from tests.helpers.procs import cluster
from tests.programs._grid import WORLD, start_robots, start_world, write_grid

pytestmark = pytest.mark.processes

BASE = (6, 6)


def small_field(tmp_path: Path, seed: int = 7) -> tuple[Path, int]:
    """12x12, 5 % obstacles, 2 resources of 500 units; the base in the centre."""
    grid = random_obstacles(12, 12, 0.05, seed, keep_free=(BASE,))
    resources = place_resources(grid, 2, 500, seed + 1, exclude=(BASE,), reachable_from=BASE)
    return write_grid(tmp_path / "field.json", grid.obstacles, BASE, resources), 1000


async def test_four_robot_processes_forage_to_completion(tmp_path: Path) -> None:
    path, total = small_field(tmp_path)
    names = ["f0", "f1", "f2", "f3"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, path, "--expect", "4", "--until", "delivered")
        await start_robots(c, names, [{"view": 0}] * 4)
        await node.membership.wait_for([WORLD, *names], timeout=20)
        t0 = time.monotonic()
        outcomes = await asyncio.wait_for(
            launch(node, "foraging", names, {"method": "cmarking", "seed": 3}, run="forage"), 90
        )
        took = time.monotonic() - t0
        results: dict[str, Any] = {n: o.get("result") for n, o in outcomes.items()}
        assert all(r and r["finished"] for r in results.values()), outcomes
        state = await node.call(WORLD, "state", timeout=5)
        assert state["remaining"] == 0 and state["carried"] == 0
        assert state["delivered"] == total
        assert sum(r["delivered"] for r in results.values()) == total
        rounds = results["f0"]["rounds"]
        assert all(r["rounds"] == rounds for r in results.values())
        text = await node.call(WORLD, "snapshot", timeout=5)  # the field as text, no file
        assert text.startswith("round ") and "remaining 0" in text and "values:" in text
        with pytest.raises(BadArguments):  # a caller cannot make the world write a file
            await node.call(WORLD, "snapshot", str(tmp_path / "field.png"), timeout=5)
        assert not (tmp_path / "field.png").exists()
        print(
            f"\nforaging: {rounds} rounds in {took:.1f} s ({rounds / took:.0f} rounds/s); "
            f"delivered {state['delivered']}; per robot {results}"
        )
        print(text)


async def test_sequential_turns_repeat_the_in_process_run_across_processes(tmp_path: Path) -> None:
    env_seed, agent_seed = (9, 1, 0), (9, 1, 0, 4, 0)
    trial = run_trial(Setup(12, 0.05, 2, 300), 4, "cmarking", env_seed, agent_seed, 20000)
    env = np.random.default_rng(np.random.SeedSequence(list(env_seed)))
    grid = random_obstacles(12, 12, 0.05, env, keep_free=(BASE,))
    resources = place_resources(grid, 2, 300, env, exclude=(BASE,))
    path = write_grid(tmp_path / "field.json", grid.obstacles, BASE, resources)
    names = ["s0", "s1", "s2", "s3"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, path, "--expect", "4", "--turns", "sequential")
        await start_robots(c, names, [{"view": 0}] * 4)
        await node.membership.wait_for([WORLD, *names], timeout=20)
        outcomes = await asyncio.wait_for(
            launch(
                node,
                "foraging",
                names,
                {"method": "cmarking", "seed": list(agent_seed)},
                run="sequential",
            ),
            90,
        )
        results: dict[str, Any] = {n: o.get("result") for n, o in outcomes.items()}
        assert all(r and r["finished"] for r in results.values()), outcomes
    print(
        f"\nsequential turns: in-process {trial.iterations} iterations, robot processes "
        f"{sorted({r['rounds'] for r in results.values()})}"
    )
    assert {r["rounds"] for r in results.values()} == {trial.iterations}
