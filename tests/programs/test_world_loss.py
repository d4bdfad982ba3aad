"""A world SIGKILLed in the middle of a run, then started again (real processes).

The robots' runs end with ``WorldLost`` (reported to the launcher, no traceback in any robot's
log); the robots wait for the world, rejoin it when it is back, and run a new program.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from mover import launch
from mover.testing import cluster

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]
WORLD = str(ROOT / "worlds" / "search_and_rescue.toml")
NAMES = ["elvis", "ernst", "moseley"]


@pytest.mark.slow
async def test_robots_survive_a_world_that_dies_and_comes_back(tmp_path: Path) -> None:
    logs = {n: tmp_path / f"{n}.log" for n in NAMES}
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        world = await c.world(WORLD, expect=len(NAMES))
        await asyncio.gather(*(c.start("robots", "--name", n, log=logs[n]) for n in NAMES))
        run = asyncio.ensure_future(launch(node, "search_and_rescue", NAMES, {}, run="lost"))
        await asyncio.sleep(2.0)  # under way: searching
        assert not run.done()
        world.kill()
        await world.wait()
        outcomes = await asyncio.wait_for(run, 30)
        assert all("WorldLost" in str(o.get("error")) for o in outcomes.values()), outcomes
        await c.world(WORLD, expect=len(NAMES))  # back, with the same name
        async with asyncio.timeout(30):  # every robot rejoins it
            while not all("back in the world" in log.read_text() for log in logs.values()):
                await asyncio.sleep(0.2)
        again = await asyncio.wait_for(launch(node, "hello_team", NAMES, {}, run="again"), 60)
        assert all("result" in o for o in again.values()), again
        async with asyncio.timeout(10):  # in the new world, and idle again after the run
            while (status := await node.call("world", "status", timeout=10))["idle"] != NAMES:
                await asyncio.sleep(0.1)
        assert status["robots"] == sorted(NAMES)
        senses = await asyncio.gather(*(node.call(n, "robot.sense", timeout=10) for n in NAMES))
        times = {round(s["time"] / 0.1) for s in senses}
        assert times == {status["tick"]}, (times, status)  # the new world's clock, not the old
    for name, log in logs.items():
        text = log.read_text()
        assert "Traceback" not in text, text[-2000:]
        assert "is gone" in text and "back in the world" in text, (name, text[-2000:])
