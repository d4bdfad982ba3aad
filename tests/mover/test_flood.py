"""A member whose loop is held up for 20 s while a flood of broadcasts comes in (real processes).

Its hand-off from zenoh's threads is bounded (``mover._bridge``: 64 MiB of broadcasts, then
they are dropped and counted), so its memory stays bounded, and it serves calls again at once.
"""

from __future__ import annotations

import asyncio
import time

import pytest

from mover import Node
from tests.helpers.procs import cluster

pytestmark = pytest.mark.processes

BOUND_MB = 160  # the hand-off's 64 MiB, the subscription's 1000 messages, the rest of Python


@pytest.mark.slow
async def test_a_blocked_receiver_under_a_flood_stays_bounded() -> None:
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        await c.joined("r1", node)
        before = await node.call("r1", "rss_kb", timeout=5)
        blocked = asyncio.ensure_future(node.call("r1", "block", 20.0, timeout=60))
        chunk = b"x" * 1024
        sent = 0
        end = time.monotonic() + 20.0
        while time.monotonic() < end and not blocked.done():
            for _ in range(50):
                node.broadcast_nowait("flood", chunk)
            sent += 50
            await asyncio.sleep(0)
        await blocked
        t0 = time.monotonic()
        assert await node.call("r1", "add", 1, 2, timeout=10) == 3  # serving again at once
        answered = time.monotonic() - t0
        after = await node.call("r1", "rss_kb", timeout=5)
        counted = await node.call("r1", "flooded", timeout=5)
        grown = (after - before) / 1024
        print(f"\nsent {sent} 1 KiB broadcasts in 20 s; r1 counted {counted}; grew {grown:.0f} MB")
        assert sent > 100_000  # a flood: far more than the hand-off holds
        assert grown < BOUND_MB
        assert answered < 5.0
