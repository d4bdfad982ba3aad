"""programs/levy_search.py as robot processes on a lock-step world process: the team finds
every target; FL and L repeat the in-process run of the same seed to the tick; L+P (whose
repulsion comes over range-limited broadcast, heard a tick early or late) agrees with the
in-process runs in distribution over 10 seeds."""

from __future__ import annotations

import asyncio
import json
import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from experiments.levy import Setup, arena, run_world, world_data
from mover import launch
from sim_hw.continuous import TICK, WorldSpec, load_world
from tests.helpers.procs import ROOT, cluster

pytestmark = pytest.mark.processes

SETUP = replace(Setup(), size=8.0, obstacles=3, max_time=900.0)
ROBOTS, TARGETS = 3, 2


def small_world(tmp_path: Path, run: int) -> tuple[Path, WorldSpec]:
    """An 8 × 8 m arena with 3 obstacles, 2 targets and 3 robots, as a JSON world file."""
    path = tmp_path / f"levy-{run}.json"
    path.write_text(json.dumps(world_data(arena(SETUP, ROBOTS, TARGETS, 5, run))))
    return path, load_world(path)


async def distributed(
    path: Path, method: str, seed: int, robots: int = ROBOTS, targets: int = TARGETS
) -> tuple[dict[str, Any], float]:
    """One run of the program on a fresh world and robot processes; results and wall s."""
    names = [f"r{i:02d}" for i in range(robots)]
    async with cluster() as c, c.launcher() as node:
        await c.world(str(path), expect=robots)
        await c.robots(*names)
        await node.membership.wait_for(["world", *names], timeout=60)
        args = {"method": method, "targets": targets, "seed": seed, "max_time": SETUP.max_time}
        t0 = time.monotonic()
        outcomes = await asyncio.wait_for(launch(node, "levy_search", names, args, run="levy"), 500)
        took = time.monotonic() - t0
    results = {n: o.get("result") for n, o in outcomes.items()}
    assert all(r is not None for r in results.values()), outcomes
    return results, took


def ticks(t: float | None) -> int | None:
    return None if t is None else round(t / TICK)


@pytest.mark.parametrize("method", ["FL", "L"])
async def test_fl_and_l_repeat_the_in_process_run_to_the_tick(tmp_path: Path, method: str) -> None:
    path, spec = small_world(tmp_path, 3)  # a run whose L walk takes ~160 s
    reference = run_world(spec, method, SETUP, [11])
    assert reference["time"] is not None
    results, took = await distributed(path, method, 11)
    got = {ticks(r["time"]) for r in results.values()}
    finds = sorted(
        min(r["found"][t] for r in results.values() if t in r["found"])
        for t in {t for r in results.values() for t in r["found"]}
    )
    print(
        f"\n{method}: in-process {reference['time']:.1f} s, distributed "
        f"{sorted(r['time'] for r in results.values())} s, {took:.1f} s wall"
    )
    assert got == {ticks(reference["time"])}
    assert [ticks(t) for t in finds] == [ticks(t) for t in reference["found"]]
    marked = sorted(t for r in results.values() for t in r["marked"])
    assert len(marked) >= TARGETS


@pytest.mark.timeout(400)
async def test_l_plus_p_agrees_with_the_in_process_runs_over_10_seeds(tmp_path: Path) -> None:
    here, there = [], []
    walls = []
    for run in range(10):
        path, spec = small_world(tmp_path, run)
        reference = run_world(spec, "L+P", SETUP, [run])
        results, took = await distributed(path, "L+P", run)
        walls.append(took)
        times = {r["time"] for r in results.values()}
        assert len(times) == 1 and None not in times, results
        here.append(reference["time"])
        there.append(times.pop())
    a, b = np.array(here), np.array(there)
    se = math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
    same = int(np.sum(np.round(a / TICK) == np.round(b / TICK)))
    print(
        f"\nL+P over 10 seeds: in-process {a.mean():.1f} ± {a.std(ddof=1):.1f} s, distributed "
        f"{b.mean():.1f} ± {b.std(ddof=1):.1f} s; difference {b.mean() - a.mean():+.1f} s "
        f"(se {se:.1f}); identical to the tick in {same}/10; {sum(walls):.0f} s wall"
    )
    print("in-process", [round(x, 1) for x in here])
    print("distributed", [round(x, 1) for x in there])
    assert abs(b.mean() - a.mean()) < 3 * se + 1.0
    # the paired runs share arena, starts and walks: they should mostly stay close
    assert float(np.median(np.abs(a - b))) < 0.5 * float(np.median(a))


@pytest.mark.slow
@pytest.mark.timeout(900)
async def test_ten_robot_processes_search_the_papers_arena() -> None:
    path = ROOT / "worlds" / "levy_search.json"  # 20 x 20 m, 12 obstacles, 8 targets
    spec = load_world(path)
    setup = Setup()
    for method in ("L", "L+P"):
        reference = run_world(spec, method, setup, [11])
        results, took = await distributed(path, method, 11, robots=10, targets=8)
        times = sorted({r["time"] for r in results.values()})
        sim = reference["time"]
        print(
            f"\n{method}, 10 robot processes, 8 targets: in-process {sim:.1f} s, distributed "
            f"{[round(t, 1) for t in times]} s in {took:.1f} s wall ({10 * times[-1] / took:.0f}"
            " simulated robot-s per wall s)"
        )
        assert len(times) == 1 and times[0] is not None
        if method == "L":
            assert ticks(times[0]) == ticks(sim)
