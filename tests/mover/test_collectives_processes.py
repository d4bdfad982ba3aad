"""The collectives across real robot processes over real zenoh on 127.0.0.1."""

from __future__ import annotations

import asyncio
import os
import sys
import time
from pathlib import Path

import pytest

from mover import Node, NodeConfig, Refused, TeamCredentials, UnknownRobot, launch
from mover._config import free_port
from tests.helpers.procs import Cluster, cluster

pytestmark = pytest.mark.processes


async def start_team(
    c: Cluster, node: Node, names: list[str], config: NodeConfig | None = None
) -> None:
    await asyncio.gather(
        *(c.start("tests.helpers.team_proc", "--name", n, config=config) for n in names)
    )
    await node.membership.wait_for(names, timeout=30)


async def test_ties_always_agree_on_one_winner_10_processes_100_rounds() -> None:
    names = [f"m{i}" for i in range(10)]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_team(c, node, names)
        start = time.time() + 1.0
        outcomes = await launch(
            node, "ties", names, {"rounds": 100, "start": start, "gap": 0.03}, run="ties"
        )
        winners = [o["result"] for o in outcomes.values()]
        assert all(w == winners[0] for w in winners), "members disagreed"
        assert len(winners[0]) == 100
        print(f"distinct winners over 100 tied rounds: {sorted(set(winners[0]))}")


async def test_losers_clean_up(tmp_path: Path) -> None:
    names = ["a", "b", "c", "d"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_team(c, node, names)
        outcomes = await launch(
            node, "cleanup", names, {"winner": "c", "marker_dir": str(tmp_path)}, run="clean"
        )
        assert {o["result"] for o in outcomes.values()} == {"c:the box"}
        for loser in ("a", "b", "d"):
            assert (tmp_path / loser).read_text() == "cleaned"
        assert not (tmp_path / "c").exists()


async def test_sigkilled_member_during_and_survivors_told_within_a_second() -> None:
    names = ["a", "b", "c", "d"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_team(c, node, names)
        victim = c.procs[names.index("b")]
        done = asyncio.ensure_future(launch(node, "and_wait", names, {"slow": "b"}, run="kill"))
        await asyncio.sleep(0.5)
        killed = time.time()
        victim.kill()
        outcomes = await asyncio.wait_for(done, 10)
        for name in ("a", "c", "d"):
            result = outcomes[name]["result"]
            assert result.startswith("lost ['b']"), result
            told = float(result.rsplit(" ", 1)[1]) - killed
            print(f"{name} told after {told * 1000:.0f} ms")
            assert told < 1.0
        assert "error" in outcomes["b"]


CYCLES = int(os.environ.get("MOVER_OUTAGE_CYCLES", "2"))  # 20 for the figure


@pytest.mark.slow
async def test_router_restarts_mid_step_never_lose_a_live_member() -> None:
    """The router all members go through is killed while every operation runs and started again
    (``CYCLES`` times, OR and AND alternately): every step completes with the right result, and
    no live member is ever reported lost."""
    names = ["a", "b", "c"]
    router_port = free_port()
    client = NodeConfig(mode="client", listen=(), connect=(f"tcp/127.0.0.1:{router_port}",))

    async def router() -> asyncio.subprocess.Process:
        proc = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "mover._cli",
            "router",
            "--listen",
            f"tcp/127.0.0.1:{router_port}",
            stdout=asyncio.subprocess.PIPE,
        )
        assert proc.stdout is not None
        await asyncio.wait_for(proc.stdout.readline(), 20)
        return proc

    r = await router()
    spurious = 0
    try:
        async with cluster() as c, Node("launcher", c.team, kind="tool", config=client) as node:
            await start_team(c, node, names, config=client)
            for cycle in range(2 * CYCLES):
                program = "and_outage" if cycle % 2 else "or_outage"
                done = asyncio.ensure_future(
                    launch(node, program, names, {"hold": 1.0}, run=f"cut{cycle}")
                )
                await asyncio.sleep(0.4)
                r.kill()  # the network is gone while every operation is still running
                await r.wait()
                await asyncio.sleep(1.8)
                r = await router()  # and back
                outcomes = await asyncio.wait_for(done, 60)
                results = {n: o.get("result") for n, o in outcomes.items()}
                if program == "or_outage":
                    expected: object = {n: "a" for n in names}  # a finishes first
                else:
                    expected = {n: {"a": "A", "b": "B", "c": "C"} for n in names}
                spurious += sum("MemberLost" in str(o.get("error", "")) for o in outcomes.values())
                assert results == expected, (cycle, outcomes)
                await node.membership.wait_for(names, timeout=20)
    finally:
        r.kill()
        await r.wait()
    print(f"\n{2 * CYCLES} router restarts mid-step (OR and AND): {spurious} spurious MemberLost")
    assert spurious == 0


async def test_an_outsider_cannot_start_a_program() -> None:
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_team(c, node, ["a"])
        async with Node("intruder", TeamCredentials.generate("alpha"), config=c.peer) as outsider:
            await asyncio.sleep(0.5)
            with pytest.raises((Refused, UnknownRobot)):
                await outsider.call(
                    "a",
                    "mover.start",
                    "ties",
                    "evil",
                    ["a"],
                    {"rounds": 1, "start": 0.0, "gap": 0.0},
                    timeout=5,
                )
        with pytest.raises(Exception, match="no run 'evil'"):
            await node.call("a", "mover.outcome", "evil", timeout=5)


async def test_a_program_error_carries_its_traceback_to_the_launcher() -> None:
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_team(c, node, ["a"])
        outcomes = await launch(node, "divide", ["a"], {"by": 0}, run="bug")
        outcome = outcomes["a"]
        assert outcome["error"] == "ZeroDivisionError: division by zero"
        assert "team_proc.py" in outcome["traceback"] and "in divide" in outcome["traceback"]
        assert "return 1 / by" in outcome["traceback"]
