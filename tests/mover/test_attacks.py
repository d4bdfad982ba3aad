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

import pytest
import pytest_asyncio

from mover import Node
from tests.helpers.procs import Cluster, cluster

pytestmark = pytest.mark.asyncio(loop_scope="module")

SECRET = "the-rescue-code-4711"
BOUND = 1.0  # seconds: no call may take longer while the outsider is at work


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def world() -> AsyncIterator[tuple[Cluster, Node]]:
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        await c.robot("r1")
        await node.team.wait_for({"r1"}, timeout=10)
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
