"""Idle robots and liveness with real processes: a lock-step world and robot processes.

* Robots that run nothing are idle: the world's tick does not advance, and it costs nothing.
* One robot engaged in a run ticks the world while the other stays idle.
* A robot whose event loop is blocked for 3 s (a starved CPU; its process is still a member)
  is waited for, not dropped, and the run goes on.
* A robot SIGSTOPped for 3 s misses its lease: zenoh sees it leave, the world drops it after
  its grace; the others' run goes on without it, and after SIGCONT it rejoins the world.
"""

from __future__ import annotations

import asyncio
import os
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from mover import Node, launch
from mover.testing import Cluster, cluster
from tests.helpers.procs import ROOT

FIELD = """
[generator]
kind = "random_obstacles"
size = [6.0, 6.0]
count = 0
"""

pytestmark = [pytest.mark.processes, pytest.mark.timeout(120)]


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds process ``pid`` has used so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


async def _world_and_robots(
    c: Cluster, tmp: Path, names: list[str]
) -> tuple[asyncio.subprocess.Process, list[asyncio.subprocess.Process]]:
    path = tmp / "field.toml"
    path.write_text(FIELD)
    world = await c.start(
        "mover._cli",
        "world",
        str(path),
        "--lockstep",
        "--expect",
        str(len(names)),
        "--timeout",
        "1",
        ready=None,
        log=tmp / "world.log",
    )
    robots = await asyncio.gather(
        *(c.start("tests.robots.program_robot", n, log=tmp / f"{n}.log") for n in names)
    )
    return world, list(robots)


async def _status(node: Node) -> dict[str, Any]:
    status: dict[str, Any] = await node.call("world", "status", timeout=10)
    return status


async def _until(node: Node, ok: Any, limit: float = 30.0) -> dict[str, Any]:
    async with asyncio.timeout(limit):
        while not ok(status := await _status(node)):
            await asyncio.sleep(0.1)
    return status


async def test_idle_robots_hold_the_world_still_and_one_run_ticks_it(tmp_path: Path) -> None:
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        world, _ = await _world_and_robots(c, tmp_path, ["a", "b"])
        await _until(node, lambda s: s["idle"] == ["a", "b"])
        before, cpu = (await _status(node))["tick"], cpu_seconds(world.pid)
        await asyncio.sleep(2.0)
        used = cpu_seconds(world.pid) - cpu
        assert (await _status(node))["tick"] == before  # held still
        print(f"\nworld process, both robots idle: {used:.2f} CPU-s in 2 s")
        assert used < 0.3
        outcomes = await asyncio.wait_for(
            launch(node, "walk", ["a"], {"ticks": 30}, run="alone"), 60
        )
        result = outcomes["a"]["result"]
        assert result["end"] - result["start"] == pytest.approx(3.0)
        status = await _until(node, lambda s: s["idle"] == ["a", "b"])
        assert status["tick"] >= before + 30 and status["dropped"] == []


async def test_a_robot_whose_loop_stalls_is_waited_for(tmp_path: Path) -> None:
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        await _world_and_robots(c, tmp_path, ["a", "b"])
        await _until(node, lambda s: s["idle"] == ["a", "b"])
        args = {"ticks": 20, "staller": "a", "stall": 3.0}
        start = time.monotonic()
        outcomes = await asyncio.wait_for(launch(node, "walk", ["a", "b"], args, run="st"), 60)
        assert time.monotonic() - start > 3.0
        assert all("result" in o for o in outcomes.values()), outcomes
        for outcome in outcomes.values():  # 20 ticks each, a's stall included
            assert outcome["result"]["end"] - outcome["result"]["start"] == pytest.approx(2.0)
        assert outcomes["a"]["result"] == outcomes["b"]["result"]  # begun on the same tick
        assert (await _status(node))["dropped"] == []
    text = (tmp_path / "world.log").read_text()
    assert "waiting for robot a" in text and "dropped" not in text, text[-2000:]


async def test_a_sigstopped_robot_is_dropped_and_rejoins(tmp_path: Path) -> None:
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        _, (a, _) = await _world_and_robots(c, tmp_path, ["a", "b"])
        await _until(node, lambda s: s["idle"] == ["a", "b"])
        run = asyncio.ensure_future(
            launch(node, "walk", ["a", "b"], {"ticks": 100_000}, run="stop")
        )
        await _until(node, lambda s: s["tick"] > 5)
        a.send_signal(signal.SIGSTOP)
        try:
            status = await _until(node, lambda s: s["dropped"] == ["a"], limit=10)
            ticked = status["tick"]
            await asyncio.sleep(0.5)
            assert (await _status(node))["tick"] > ticked  # b's run goes on without a
        finally:
            a.send_signal(signal.SIGCONT)
        log = tmp_path / "a.log"
        async with asyncio.timeout(30):
            while "back in the world" not in log.read_text():
                await asyncio.sleep(0.2)
        await _until(node, lambda s: "a" in s["robots"])
        run.cancel()
    text = log.read_text()
    assert "Traceback" not in text, text[-2000:]
