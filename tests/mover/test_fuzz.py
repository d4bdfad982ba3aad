"""50,000 fuzzed and mutated frames at a member process: it stays alive, bounded and quiet.

Frames go to the member's broadcast, control and call keys: random bytes, truncated and
bit-flipped sealed frames, sealed frames (from a verified member, so they pass the door) whose
payloads have every wrong shape, a counter that jumps by 2**62, malformed OR decisions. Calls
are checked all along; at the end every listener of the member is alive, its memory grew by
less than ``RSS_BOUND_MB`` and its log holds no traceback.
"""

from __future__ import annotations

import asyncio
import os
import random
import sys
import time
from pathlib import Path

import pytest

from mover import Node
from mover._collective._step import DECIDED_TOPIC
from mover._wire import pack
from tests.helpers.procs import ROOT, cluster

pytestmark = pytest.mark.processes

FRAMES = 50_000
RSS_BOUND_MB = 50
SEED = 2026

WRONG = [
    None,
    1,
    -1,
    2**63,
    1.5,
    float("nan"),
    "x",
    b"\x00" * 7,
    [],
    [1],
    [1, 2, 3],
    {},
    {"ok": 1},
    {"err": "x"},
    ["a", ["b", [1, 2], 3]],
    [["x", [1e308, "y", None], -5]],
    ["news", [["data", ["nan", 2], "far"]]],
    ["news", [[1, [1.0, 2.0, 0.0], 1e9]], "extra"],
    list(range(200)),
]


def _frames(node: Node, team: str, rng: random.Random) -> list[tuple[str, str, bytes | bytearray]]:
    """(how, key, frame) triples: how is put or get."""
    sealer = node._sealer
    bc = f"mover/{team}/bc"
    keys = [f"{bc}/news", f"{bc}/flood", f"{bc}/{DECIDED_TOPIC}", f"mover/{team}/ctl/r1"]
    rpc = f"mover/{team}/rpc/r1"
    epoch = node._sessions.verified("r1") or b""
    out: list[tuple[str, str, bytes | bytearray]] = []
    frame: bytes | bytearray
    for i in range(FRAMES):
        kind = i % 8
        key = keys[i % len(keys)]
        if kind == 0:
            frame = rng.randbytes(rng.randint(0, 300))
        elif kind == 1:
            frame = sealer.seal("bc", ["news", [[i, None, None]]])[: rng.randint(0, 60)]
        elif kind == 2:
            good = bytearray(sealer.seal("bc", ["news", [[i, None, None]]]))
            good[rng.randrange(len(good))] ^= 1 << rng.randrange(8)
            frame = bytes(good)
        elif kind == 3:  # a verified member's frame with a wrong payload
            frame = sealer.seal_packed(rng.choice(["bc", "cancel", "x"]), pack(rng.choice(WRONG)))
        elif kind == 4:  # broadcast items of every wrong shape
            frame = sealer.seal("bc", [rng.choice(["news", "flood"]), [rng.choice(WRONG)] * 3])
        elif kind == 5:  # malformed decisions
            bad = [rng.choice(WRONG), rng.choice(WRONG), rng.choice(WRONG)]
            frame = sealer.seal("bc", [DECIDED_TOPIC, [[bad, None, None]]])
            key = f"{bc}/{DECIDED_TOPIC}"
        elif kind == 6:  # calls of every wrong shape, addressed properly
            payload = rng.choice([*WRONG, ["add", ["1", 2], {}], ["nope", [], {}]])
            frame = sealer.seal("call", payload, i, to="r1", to_epoch=epoch)
            out.append(("get", rpc, frame))
            continue
        else:  # random bytes at the call key
            out.append(("get", rpc, rng.randbytes(rng.randint(0, 100))))
            continue
        out.append(("put", key, frame))
        if i == FRAMES // 2:
            sealer._counter += 2**62  # a counter that jumps far ahead
    return out


async def _heard(node: Node, topic: str) -> list[object]:
    return [h[1] for h in await node.call("r1", "heard", topic, timeout=5)]


@pytest.mark.slow
async def test_fuzzed_frames_leave_a_member_alive_bounded_and_quiet(tmp_path: Path) -> None:
    log = tmp_path / "r1.log"
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        env = {**os.environ, **c.env, **c.team.env(), **c.peer.env()}
        with log.open("wb") as err:
            proc = await asyncio.create_subprocess_exec(
                sys.executable, "-m", "tests.helpers.robot_proc", "--name", "r1",
                stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE, stderr=err,
                env=env, cwd=ROOT,
            )  # fmt: skip
        c.procs.append(proc)
        await node.membership.wait_for({"r1"}, timeout=15)
        assert await node.call("r1", "add", 1, 2, timeout=5) == 3
        before = await node.call("r1", "rss_kb", timeout=5)
        session = node.zenoh_session
        rng = random.Random(SEED)
        frames = _frames(node, c.team.name, rng)
        t0 = time.monotonic()
        for k, (how, key, frame) in enumerate(frames):
            if how == "put":
                session.put(key, frame)
            else:
                session.get(key, lambda reply: None, payload=frame, timeout=2.0)
            if k % 2000 == 0:
                await asyncio.sleep(0)
                assert await node.call("r1", "add", k, 1, timeout=10) == k + 1
        took = time.monotonic() - t0
        await asyncio.sleep(1.0)
        assert await node.call("r1", "add", 20, 22, timeout=10) == 42
        assert await node.call("r1", "listening", timeout=5) is True
        grown = (await node.call("r1", "rss_kb", timeout=5) - before) / 1024
        node.broadcast_nowait("news", "still there")
        async with asyncio.timeout(10):
            while "still there" not in [
                h[1] for h in await node.call("r1", "heard", "news", timeout=5)
            ]:
                await asyncio.sleep(0.1)
                node.broadcast_nowait("news", "still there")
        print(f"\n{FRAMES} frames (seed {SEED}) in {took:.1f} s; r1 grew {grown:.1f} MB")
        assert grown < RSS_BOUND_MB
    text = log.read_text(errors="replace")
    assert "Traceback" not in text, text[-3000:]
    assert text.count("\n") < 2000  # rate-limited: not a line per frame
