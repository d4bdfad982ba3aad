"""Integration tests of the mover core: real OS processes over real zenoh on 127.0.0.1.

One module-wide cluster: this test process (a member at (100, 100), far from everyone) and three
robot processes at known positions:

    r1 (0, 0) heading 0      r2 (3, 4) heading pi/2      r3 (6, 8) heading pi

|r1 r2| = 5, |r2 r3| = 5, |r1 r3| = 10.
"""

from __future__ import annotations

import asyncio
import math
import os
import signal
import sys
import time
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio
import zenoh

from mover import (
    BadArguments,
    CallTimeout,
    FixedLocator,
    Node,
    PayloadTooLarge,
    RemoteError,
    RobotLost,
    TeamCredentials,
    UnknownProcedure,
    UnknownRobot,
)
from mover._wire import Opener, Sealer, read_refusal
from tests.helpers.procs import Cluster, cluster

pytestmark = [pytest.mark.processes, pytest.mark.asyncio(loop_scope="module")]

POSITIONS = {"r1": (0.0, 0.0, 0.0), "r2": (3.0, 4.0, math.pi / 2), "r3": (6.0, 8.0, math.pi)}


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def world() -> AsyncIterator[tuple[Cluster, Node]]:
    async with (
        cluster() as c,
        Node(
            "tester", c.team, kind="test", config=c.seed, locator=FixedLocator(100.0, 100.0)
        ) as node,
    ):
        await asyncio.gather(
            *(
                c.robot(name, "--x", str(x), "--y", str(y), "--heading", str(h))
                for name, (x, y, h) in POSITIONS.items()
            )
        )
        await node.membership.wait_for(POSITIONS, timeout=10)
        yield c, node


async def test_rpc_across_processes(world: tuple[Cluster, Node]) -> None:
    _, node = world
    assert await node.call("r1", "add", 2, 3, timeout=5) == 5
    # robot to robot, through a third process's request
    assert await node.call("r1", "call_other", "r2", "add", [40, 2], timeout=5) == 42
    info = node.membership.info("r2")
    assert info is not None and info.kind == "robot" and info.uptime >= 0


async def test_remote_exception_is_typed(world: tuple[Cluster, Node]) -> None:
    _, node = world
    with pytest.raises(RemoteError) as err:
        await node.call("r2", "boom", "the wheel fell off", timeout=5)
    assert err.value.remote_type == "ValueError"
    assert err.value.message == "the wheel fell off"
    assert err.value.robot == "r2"


async def test_timeout(world: tuple[Cluster, Node]) -> None:
    _, node = world
    started = time.monotonic()
    with pytest.raises(CallTimeout):
        await node.call("r3", "sleep", 5.0, timeout=0.3)
    assert time.monotonic() - started < 2.0
    assert await node.call("r3", "add", 1, 1, timeout=5) == 2  # still serving


async def test_cancellation_reaches_the_callee(world: tuple[Cluster, Node], tmp_path: Path) -> None:
    _, node = world
    marker = tmp_path / "hold"
    task = asyncio.create_task(node.call("r1", "hold", str(marker), timeout=None))
    await _until(lambda: marker.exists() and marker.read_text() == "started")
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    await _until(lambda: marker.read_text() == "cleaned")


async def test_bad_arguments_and_unknown_procedure(world: tuple[Cluster, Node]) -> None:
    _, node = world
    with pytest.raises(BadArguments, match="argument 'x': expected int"):
        await node.call("r1", "add", "two", 3, timeout=5)
    with pytest.raises(BadArguments, match="missing a required argument"):
        await node.call("r1", "add", 2, timeout=5)
    with pytest.raises(UnknownProcedure, match="exports no procedure 'fly'"):
        await node.call("r1", "fly", timeout=5)
    with pytest.raises(UnknownRobot):
        await node.call("nobody", "add", 1, 2, timeout=5)
    assert await node.call("r1", "add", 2, 3, timeout=5) == 5


async def test_oversized_payload(world: tuple[Cluster, Node]) -> None:
    _, node = world
    with pytest.raises(PayloadTooLarge):
        await node.call("r1", "echo", b"x" * (5 * 1024 * 1024), timeout=5)
    assert await node.call("r1", "echo", b"x" * 65536, timeout=5) == 65536


async def _until_routes_are_up(node: Node) -> None:
    """Probe team-wide until every robot hears the others and the tester hears r3: the
    subscriptions (the tester's declared before the probe's) have reached everyone."""
    probe = node.subscribe("probe")
    try:
        async with asyncio.timeout(15):
            while True:
                for r in POSITIONS:
                    await node.call(r, "send", "probe", 0, None, timeout=5)
                await asyncio.sleep(0.1)
                heard = {
                    r: {h[0] for h in await node.call(r, "heard", "probe", timeout=5)}
                    for r in POSITIONS
                }
                if "r3" in {m.sender for m in probe.drain()} and all(
                    heard[r] >= set(POSITIONS) - {r} for r in POSITIONS
                ):
                    return
    finally:
        probe.close()


async def test_range_limited_broadcast(world: tuple[Cluster, Node]) -> None:
    _, node = world
    mine = node.subscribe("news")
    await _until_routes_are_up(node)
    await node.call("r1", "send", "news", {"from": "r1"}, 6.0, timeout=5)
    await node.call("r2", "send", "news", {"from": "r2"}, 5.5, timeout=5)
    await node.call("r3", "send", "news", {"from": "r3"}, None, timeout=5)
    expected = {"r1": ["r2", "r3"], "r2": ["r1", "r3"], "r3": ["r2"]}
    async with asyncio.timeout(10):  # a loaded machine may take a while to deliver
        while True:
            heard = {r: await node.call(r, "heard", "news", timeout=5) for r in POSITIONS}
            senders = {r: sorted(h[0] for h in heard[r]) for r in heard}
            if all(len(senders[r]) >= len(expected[r]) for r in expected):
                break
            await asyncio.sleep(0.05)
    assert senders == expected
    by = {(r, h[0]): h for r in heard for h in heard[r]}
    # distance and bearing in the receiver's frame
    _, _, dist, bearing = by[("r2", "r1")]
    assert dist == pytest.approx(5.0)
    assert bearing == pytest.approx(_wrap(math.atan2(-4, -3) - math.pi / 2))
    _, _, dist, bearing = by[("r3", "r2")]
    assert dist == pytest.approx(5.0)
    assert bearing == pytest.approx(_wrap(math.atan2(-4, -3) - math.pi))
    _, _, dist, bearing = by[("r1", "r2")]
    assert bearing == pytest.approx(math.atan2(4, 3))
    # the team-wide one reached the far tester too; the ranged ones did not
    got = [(await mine.get(timeout=10)).sender] + [m.sender for m in mine.drain()]
    assert got == ["r3"]
    assert node.neighbours(max_age=5.0)["r3"].distance == pytest.approx(math.hypot(94, 92))


async def test_outsiders_are_refused(world: tuple[Cluster, Node]) -> None:
    c, node = world
    before = await node.call("r1", "bumps", timeout=5)
    for team in (TeamCredentials.generate("alpha"), TeamCredentials.generate("beta")):
        await c.start("tests.helpers.outsider", "r1", team=team, ready="DONE")
    await asyncio.sleep(0.3)
    assert await node.call("r1", "bumps", timeout=5) == before  # nothing ran
    heard = await node.call("r1", "heard", "chatter", timeout=5)
    assert heard == []  # the injected broadcast was dropped
    assert "outsider" not in node.membership.members()


async def test_replayed_envelope_is_refused(world: tuple[Cluster, Node]) -> None:
    c, node = world
    before = await node.call("r2", "bumps", timeout=5)
    sealer = Sealer(c.team.name, "tester", c.team.key)
    r2 = node._sessions.verified("r2")  # the session the tester verified r2 in
    assert r2 is not None
    frame = sealer.seal("call", ["bump", [], {}], 999_999, to="r2", to_epoch=r2)
    answers = [await _raw_get(node, "mover/alpha/rpc/r2", frame) for _ in range(2)]
    opener = Opener(c.team.name, c.team.key)
    first = opener.open(answers[0])  # the sealed answer, to the tester
    assert first.recipient == "tester" and "ok" in first.payload
    # The replay: the same sealed answer again, and the procedure not run again (an outsider
    # whose copy of a call comes first must not leave the original unanswered; nor is a
    # refusal ever sealed, which an outsider relaying the call could hand back to end the
    # caller's call: test_reflection.py)
    assert answers[1] == answers[0]
    assert await node.call("r2", "bumps", timeout=5) == before + 1
    # the same call overheard on its way to r2 and sent to r3: refused, r3 runs nothing
    before3 = await node.call("r3", "bumps", timeout=5)
    other = await _raw_get(node, "mover/alpha/rpc/r3", frame)
    assert "not for 'r3'" in (read_refusal(other) or "")
    unaddressed = sealer.seal("call", ["bump", [], {}], 1_000_000)  # for no one in particular
    blank = await _raw_get(node, "mover/alpha/rpc/r3", unaddressed)
    assert read_refusal(blank) is not None
    assert await node.call("r3", "bumps", timeout=5) == before3


@pytest.mark.parametrize(
    ("frame", "why"),
    [
        (b"\x93\x01\x02", b"not a sealed mover frame"),
        (b"M2\x00\x04" + b"\xc1\xc1\xc1\xc1" * 4 + b"\x00" * 32, b"malformed msgpack"),
        (
            Sealer("alpha", "mallory", b"k" * 32).seal("call", ["add", [1, 2], {}], 1, to="r3"),
            b"bad signature",
        ),
        (b"M2" + b"\x00" * (5 * 1024 * 1024), b"over the limit"),
    ],
    ids=["malformed-msgpack", "malformed-header", "forged-signature", "oversized"],
)
async def test_bad_frames_get_a_refusal_and_the_robot_keeps_serving(
    world: tuple[Cluster, Node], frame: bytes, why: bytes
) -> None:
    _, node = world
    answer = await _raw_get(node, "mover/alpha/rpc/r3", frame)
    assert answer.startswith(b"MR") and why in answer
    assert await node.call("r3", "add", 1, 2, timeout=5) == 3


async def test_signed_but_malformed_body_is_refused(world: tuple[Cluster, Node]) -> None:
    c, node = world
    frame = Sealer(c.team.name, "tester", c.team.key).seal_packed(
        "call", b"\xc1\xc1garbage", to="r3"
    )
    answer = await _raw_get(node, "mover/alpha/rpc/r3", frame)
    assert answer.startswith(b"MR") and b"malformed msgpack" in answer
    assert await node.call("r3", "add", 1, 2, timeout=5) == 3


async def test_sigkilled_member_is_seen_gone_and_its_call_fails(
    world: tuple[Cluster, Node], tmp_path: Path
) -> None:
    c, node = world
    proc = await c.joined("victim", node)
    marker = tmp_path / "m"
    call = asyncio.create_task(node.call("victim", "hold", str(marker), timeout=None))
    await _until(lambda: marker.exists())
    killed = time.monotonic()
    proc.kill()
    with pytest.raises(RobotLost):
        await call
    failed = time.monotonic() - killed
    await node.membership.wait_gone("victim", timeout=1.0)
    gone = time.monotonic() - killed
    print(
        f"SIGKILL: call failed after {failed * 1000:.1f} ms, member gone after {gone * 1000:.1f} ms"
    )
    assert failed < 1.0
    assert gone < 1.0  # typically a few ms (the kernel closes the socket)


@pytest.mark.skipif(sys.platform != "linux", reason="SIGSTOP semantics")
async def test_hung_member_is_seen_gone_within_about_a_second(
    world: tuple[Cluster, Node],
) -> None:
    c, node = world
    proc = await c.joined("sleeper", node)
    stopped = time.monotonic()
    os.kill(proc.pid, signal.SIGSTOP)
    try:
        await node.membership.wait_gone("sleeper", timeout=3.0)
        print(f"SIGSTOP: member gone after {(time.monotonic() - stopped) * 1000:.0f} ms")
        assert time.monotonic() - stopped < 2.0
    finally:
        os.kill(proc.pid, signal.SIGKILL)


# -- helpers -------------------------------------------------------------------------------------


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


async def _until(predicate: object, timeout: float = 5.0) -> None:
    async with asyncio.timeout(timeout):
        while not predicate():  # type: ignore[operator]
            await asyncio.sleep(0.01)


async def _raw_get(node: Node, key: str, frame: bytes | bytearray) -> bytes:
    """A raw zenoh get (no mover client), returning the first reply's bytes."""

    def get() -> bytes:
        replies = node.zenoh_session.get(
            key, payload=frame, consolidation=zenoh.ConsolidationMode.NONE, timeout=5.0
        )
        for reply in replies:
            if reply.ok is not None:
                return bytes(reply.ok.payload.to_bytes())
        return b""

    return await asyncio.to_thread(get)
