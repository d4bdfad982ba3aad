"""The one door between zenoh's threads and asyncio: coalesced wake-ups, errors contained."""

from __future__ import annotations

import asyncio
import threading

import pytest

from mover._bridge import Portal, run_blocking


async def test_a_burst_costs_few_loop_hops_and_keeps_order() -> None:
    portal = Portal(asyncio.get_running_loop())
    got: list[int] = []
    done = asyncio.Event()

    def handler(item: int) -> None:
        got.append(item)
        if item == 9999:
            done.set()

    def burst() -> None:
        for i in range(10_000):
            portal.send(handler, i)

    thread = threading.Thread(target=burst)
    thread.start()
    await asyncio.wait_for(done.wait(), 10)
    thread.join()
    assert got == list(range(10_000))
    assert portal.hops < 1000  # far fewer wake-ups than items


async def test_a_failing_handler_is_logged_not_raised(caplog: pytest.LogCaptureFixture) -> None:
    portal = Portal(asyncio.get_running_loop())
    got: list[int] = []

    def bad(item: int) -> None:
        raise ValueError("boom")

    portal.send(bad, 1)
    portal.send(got.append, 2)
    await asyncio.sleep(0.05)
    assert got == [2]
    assert "handler" in caplog.text and "boom" in caplog.text


async def test_run_blocking_returns_and_raises() -> None:
    assert await run_blocking(lambda: 41 + 1) == 42

    def fail() -> None:
        raise OSError("no")

    with pytest.raises(OSError, match="no"):
        await run_blocking(fail)


async def test_the_hand_off_is_bounded_in_items_and_bytes() -> None:
    portal = Portal(asyncio.get_running_loop(), limit=5, limit_bytes=1000)
    got: list[int] = []
    for i in range(20):  # the loop is held up: nothing drains meanwhile
        portal.send(got.append, i, droppable=True)
    assert portal.dropped == 15
    for i in range(20):  # other items are kept up to twice the bound, then dropped too
        portal.send(got.append, 100 + i)
    assert portal.overflowed == 15
    await asyncio.sleep(0)
    assert got == [0, 1, 2, 3, 4, 100, 101, 102, 103, 104]
    for i in range(5):  # a few large items: the byte bound
        portal.send(got.append, 200 + i, droppable=True, size=400)
    assert portal.dropped == 15 + 2
    await asyncio.sleep(0)
    assert got[-3:] == [200, 201, 202]
