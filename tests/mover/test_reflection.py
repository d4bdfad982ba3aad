"""An outsider with no team key relaying every frame it can reach back at the team (issue 24):
each call and challenge asked again of the members, each answer handed back as its own, each
cancel and broadcast put again. Among real processes, no call and no run may fail. And the
other race: an outsider on a faster path whose copy of each call reaches the callee before the
original, and which drops the callee's answer to it."""

from __future__ import annotations

import asyncio
import signal
from pathlib import Path
from typing import Any

import pytest

from mover import Node, NodeConfig, launch
from mover._impair import Impairment, ImpairProxy
from mover._rpc import WAITING
from tests.helpers.procs import cluster
from tests.mover.test_collectives_processes import start_team

pytestmark = pytest.mark.processes

ROUNDS = 10  # of 10 short and 10 long (0.3 s) calls at once: 200 calls
SLOW = 0.1  # seconds each way on the caller's link to the callee (the outsider's is direct)


@pytest.mark.timeout(120)
async def test_an_outsider_reflecting_every_frame_fails_no_call_and_no_run(
    tmp_path: Path,
) -> None:
    members = ["a", "b", "c"]
    async with cluster() as c, Node("tester", c.team, kind="tool", config=c.seed) as node:
        await c.joined("r1", node)
        await start_team(c, node, members)
        reflector = await c.start("tests.helpers.reflector", c.team.name, "--seconds", "60")
        await asyncio.sleep(0.5)  # its queryables are known to every member
        for k in range(ROUNDS):
            short = [node.call("r1", "add", k, i, timeout=10) for i in range(10)]
            long = [node.call("r1", "sleep", 0.3, timeout=10) for _ in range(10)]
            got = await asyncio.gather(*short, *long)
            assert got == [k + i for i in range(10)] + ["slept"] * 10
        ran_or = await launch(
            node, "cleanup", members, {"winner": "b", "marker_dir": str(tmp_path)}, run="or"
        )
        assert {o.get("result") for o in ran_or.values()} == {"b:the box"}, ran_or
        ran_and = await launch(node, "and_outage", members, {"hold": 0.3}, run="and")
        every = {m: m.upper() for m in members}
        assert [o.get("result") for o in ran_and.values()] == [every] * 3, ran_and
        c.kill(reflector, signal.SIGTERM)
        assert reflector.stdout is not None
        said = (await asyncio.wait_for(reflector.stdout.read(), 10)).decode().split()
    queries, answers, puts = (int(x) for x in said[1:4]) if said[:1] == ["DONE"] else (0, 0, 0)
    print(f"the outsider relayed {queries} queries, {answers} answers, {puts} puts")
    assert queries >= 200 and answers > 0, said  # the attack happened


async def copied_first(copies: int) -> tuple[list[str], list[str], Any]:
    """100 calls to r1 (10 short and 10 long at once, five times) over a link 0.1 s slower each
    way than the outsider's, which sends ``copies`` copies of each call on at once and drops the
    answers: the calls that failed, what the outsider said, how often r1 bumped (50 asked)."""
    async with cluster() as c, Node("tester", c.team, kind="tool", config=c.seed) as node:
        proxy = ImpairProxy(("127.0.0.1", c.port), up=Impairment(SLOW), down=Impairment(SLOW))
        host, port = await proxy.start()
        try:
            slow = NodeConfig(connect=(f"tcp/{host}:{port}",))
            await c.start("tests.helpers.robot_proc", "--name", "r1", config=slow)
            await node.membership.wait_for({"r1"}, timeout=10)
            reflector = await c.start(
                "tests.helpers.reflector",
                *(c.team.name, "--seconds", "60", "--first", "--copies", str(copies)),
            )
            await asyncio.sleep(1.0)  # it links to r1 directly, and its queryable is known
            failed: list[str] = []
            for _ in range(5):
                short = [node.call("r1", "bump", timeout=5) for _ in range(10)]
                long = [node.call("r1", "sleep", 0.3, timeout=5) for _ in range(10)]
                got = await asyncio.gather(*short, *long, return_exceptions=True)
                failed += [repr(g) for g in got if isinstance(g, Exception)]
            asked = await asyncio.gather(
                node.call("r1", "bumps", timeout=5), return_exceptions=True
            )
            c.kill(reflector, signal.SIGTERM)
            assert reflector.stdout is not None
            said = (await asyncio.wait_for(reflector.stdout.read(), 10)).decode().split()
        finally:
            await proxy.close()
    return failed, said, asked[0]


@pytest.mark.timeout(120)
async def test_a_copy_of_a_call_that_comes_first_with_its_answer_dropped_fails_no_call() -> None:
    """The callee runs the copy (never twice) and answers the late original with the same
    sealed answer; with a replay refused instead, every call here ended in CallTimeout."""
    failed, said, bumps = await copied_first(1)
    copies, first, _, late = (int(x) for x in said[1:5]) if said[:1] == ["DONE"] else (0,) * 4
    print(
        f"{len(failed)} of 100 calls failed; the outsider sent {copies} copies: the callee ran "
        f"{first} first, {late} came after the original; r1 bumped {bumps} times for 50 bumps"
    )
    assert first >= 50, said  # the attack happened: most copies came first
    assert not failed, failed[:3]
    assert bumps == 50, bumps  # every bump ran once, its copy and the original together


@pytest.mark.timeout(120)
async def test_more_copies_of_a_running_call_than_are_held_fail_no_call() -> None:
    """12 copies of each call come first: a callee holds 8 for a running call (``WAITING``) and
    refuses the rest, the original among them. Its caller asks again, with the same frame,
    once the query ended with no answer it believes; the copy it sends is answered (with the
    sealed answer kept) once the call is done. Before, each long call ended in CallTimeout."""
    failed, said, bumps = await copied_first(WAITING + 4)
    queries, first, _, refused = (int(x) for x in said[1:5]) if said[:1] == ["DONE"] else (0,) * 4
    print(
        f"{len(failed)} of 100 calls failed; the outsider copied {queries} calls "
        f"{WAITING + 4} times: {first} copies answered, {refused} refused; r1 bumped {bumps} times"
    )
    assert refused >= 50, said  # the attack happened: copies of the long calls were refused
    assert not failed, failed[:3]
    assert bumps == 50, bumps
