"""A hostile outsider with raw zenoh sessions and no key, against real member processes.

It declares complete queryables on a member's call key (several sessions, re-declared every
half second), answers calls with unsigned refusals or holds them, and records everything it
overhears. The member's calls must all go through, undelayed beyond a bound, with the right
results; what it overheard must hold no plaintext.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio
import zenoh

from mover import Node
from tests.helpers.procs import Cluster, cluster
from tests.mover.test_processes import _raw_get

pytestmark = [pytest.mark.processes, pytest.mark.asyncio(loop_scope="module")]

SECRET = "the-rescue-code-4711"
BOUND = 1.0  # seconds: no call may take longer while the outsider is at work


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def world() -> AsyncIterator[tuple[Cluster, Node]]:
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        await c.joined("r1", node)
        yield c, node


async def _calls_during(c: Cluster, node: Node, out: Path, *extra: str) -> list[float]:
    hijacker = await c.start(
        "tests.helpers.hijacker", c.team.name, "r1", "--seconds", "3", "--out", str(out), *extra
    )
    took = []
    end = time.monotonic() + 2.5
    while time.monotonic() < end:
        t0 = time.monotonic()
        assert await node.call("r1", "echo", SECRET.encode() * 4, timeout=5) == 4 * len(SECRET)
        assert await node.call("r1", "add", 20, 22, timeout=5) == 42
        took.append(time.monotonic() - t0)
        await node.call("r1", "send", "news", {"code": SECRET}, None, timeout=5)
    assert hijacker.stdout is not None
    done = (await asyncio.wait_for(hijacker.stdout.readline(), 10)).decode()
    assert done.startswith("DONE")
    await asyncio.wait_for(hijacker.wait(), 10)
    return took


@pytest.mark.parametrize("mode", ["refuse", "hold"])
async def test_an_outsider_captures_no_call_and_reads_no_payload(
    world: tuple[Cluster, Node], tmp_path: Path, mode: str
) -> None:
    c, node = world
    out = tmp_path / "heard.txt"
    took = await _calls_during(c, node, out, *(["--hold"] if mode == "hold" else []))
    assert len(took) >= 10 and max(took) < BOUND  # every call answered by r1, none delayed
    heard = [bytes.fromhex(line) for line in out.read_text().split()]
    calls = [h for h in heard if h[:1] == b"q"]
    print(f"\nthe outsider got {len(calls)} calls and {len(heard) - len(calls)} broadcasts")
    assert calls, "the outsider got no call: the attack did not happen"
    assert all(SECRET.encode() not in frame for frame in heard)  # no plaintext on the wire
    assert all(b"rescue" not in frame for frame in heard)
    # and once it has gone, calls go straight through
    t0 = time.monotonic()
    for _ in range(20):
        assert await node.call("r1", "add", 1, 2, timeout=5) == 3
    assert (time.monotonic() - t0) / 20 < 0.1


async def _capture(node: Node, key: str, send: Any) -> bytes:
    """The first frame that ``send()`` puts on ``key``, as an eavesdropper records it."""
    got: asyncio.Future[bytes] = asyncio.get_running_loop().create_future()
    loop = asyncio.get_running_loop()

    def on_sample(sample: Any) -> None:
        frame = bytes(sample.payload.to_bytes())

        def settle() -> None:
            if not got.done():
                got.set_result(frame)

        loop.call_soon_threadsafe(settle)

    sub = node.zenoh_session.declare_subscriber(key, on_sample)
    try:
        await asyncio.sleep(0.3)  # the subscription reaches the sender
        await send()
        return await asyncio.wait_for(got, 5)
    finally:
        sub.undeclare()


async def _heard(node: Node, robot: str, topic: str) -> list[Any]:
    return [h[1] for h in await node.call(robot, "heard", topic, timeout=5)]


async def test_a_broadcast_replayed_to_a_late_joiner_is_refused(
    world: tuple[Cluster, Node],
) -> None:
    c, node = world
    frame = await _capture(
        node,
        f"mover/{c.team.name}/bc/chatter",
        lambda: node.call("r1", "send", "chatter", "before r5 joined", None, timeout=5),
    )
    await c.joined("r5", node)
    await asyncio.sleep(0.5)  # r5 has verified r1 by now
    node.zenoh_session.put(f"mover/{c.team.name}/bc/chatter", frame)
    await node.call("r1", "send", "chatter", "after r5 joined", None, timeout=5)
    async with asyncio.timeout(10):
        while "after r5 joined" not in await _heard(node, "r5", "chatter"):
            await asyncio.sleep(0.05)
    assert await _heard(node, "r5", "chatter") == ["after r5 joined"]  # never the replay


async def test_a_call_replayed_to_a_restarted_member_is_refused(
    world: tuple[Cluster, Node],
) -> None:
    c, node = world
    proc = await c.joined("r6", node)
    key = f"mover/{c.team.name}/rpc/r6"
    overheard: list[bytes] = []

    def overhear(q: zenoh.Query) -> None:
        if q.payload is not None:  # a call always carries one
            overheard.append(bytes(q.payload.to_bytes()))
        q.drop()

    queryable = node.zenoh_session.declare_queryable(key, overhear)
    await asyncio.sleep(0.3)
    assert await node.call("r6", "bump", timeout=5) == 1
    queryable.undeclare()
    assert overheard, "the eavesdropper overheard no call"
    proc.kill()
    await proc.wait()
    await node.membership.wait_gone("r6", timeout=10)
    await c.joined("r6", node)
    answers = [await _raw_get(node, key, frame) for frame in overheard]
    assert all(a.startswith(b"M2") for a in answers)  # sealed refusals, for the tester
    assert await node.call("r6", "bumps", timeout=5) == 0  # the replay ran nothing


@pytest.mark.parametrize("skew", [3600.0, -3600.0])
async def test_a_member_whose_clock_is_an_hour_off_works(
    world: tuple[Cluster, Node], skew: float
) -> None:
    c, node = world
    name = "late" if skew > 0 else "early"
    await c.start("tests.helpers.skewed", str(skew), "tests.helpers.robot_proc", "--name", name)
    await node.membership.wait_for({name}, timeout=10)
    assert await node.call(name, "add", 1, 2, timeout=5) == 3
    assert await node.call(name, "call_other", "r1", "add", [40, 2], timeout=5) == 42
    await node.call(name, "send", "news", {"from": name}, None, timeout=5)
    async with asyncio.timeout(10):
        while {"from": name} not in await _heard(node, "r1", "news"):
            await node.call(name, "send", "news", {"from": name}, None, timeout=5)
            await asyncio.sleep(0.1)


@pytest.mark.parametrize("answer", [False, True], ids=["silent", "answering"])
async def test_2000_fake_tokens_write_a_few_log_lines_and_fail_no_call(
    tmp_path: Path, answer: bool
) -> None:
    """An outsider's raw zenoh session declares 2000 liveliness tokens under the team's prefix
    (and, ``answering``, answers every hello with junk): each member logs a few lines, not one
    per token, and the team's calls all go through meanwhile. Its tokens include one of each
    member's name, whose going must make no one leave (the member itself included). The
    members give a token up after one retry (MOVER_HELLO_RETRIES=1) so that all 2000 are given
    up within the test."""
    members = ("m1", "m2")
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        c.env["MOVER_HELLO_RETRIES"] = "1"
        logs = {m: tmp_path / f"{m}.log" for m in members}
        for m in members:
            await c.start("tests.helpers.robot_proc", "--name", m, log=logs[m])
        await node.membership.wait_for(members, timeout=10)
        before = {m: len(logs[m].read_text().splitlines()) for m in members}
        flood = await c.start(
            "tests.helpers.token_flood", c.team.name, "--tokens", "2000", "--seconds", "6",
            "--also", "m1", "--also", "m2",
            *(["--answer"] if answer else []),
        )  # fmt: skip
        calls = 0
        end = time.monotonic() + 6  # the flood's time
        while time.monotonic() < end:
            for a, b in (("m1", "m2"), ("m2", "m1")):
                got = await node.call(a, "call_other", b, "add", [calls, 1], timeout=5)
                assert got == calls + 1
            calls += 1
            await asyncio.sleep(0.02)
        await asyncio.wait_for(flood.wait(), 30)
        await asyncio.sleep(0.5)
        lines = {m: logs[m].read_text().splitlines()[before[m] :] for m in members}
        print(f"\n{calls} pairs of calls; lines per member:", {m: len(v) for m, v in lines.items()})
        for m in members:
            assert 1 <= len(lines[m]) <= 20, lines[m]  # the flood was seen, and said in few lines
            assert not [line for line in lines[m] if " left" in line], lines[m]  # none left
        assert calls >= 50  # the calls went on all along
