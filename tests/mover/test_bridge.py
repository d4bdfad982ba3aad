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
