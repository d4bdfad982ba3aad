"""``mover._futures.shielded`` keeps ``asyncio.shield``'s promises for a future."""

from __future__ import annotations

import asyncio
import gc

import pytest

from mover._futures import running_loop, shielded


async def test_the_caller_gets_the_result_the_exception_or_the_cancellation() -> None:
    loop = asyncio.get_running_loop()
    for outcome in ("result", "error", "cancelled"):
        inner: asyncio.Future[int] = loop.create_future()
        caller = asyncio.ensure_future(shielded(inner))
        await asyncio.sleep(0)
        if outcome == "result":
            inner.set_result(7)
            assert await caller == 7
        elif outcome == "error":
            inner.set_exception(KeyError("x"))
            with pytest.raises(KeyError):
                await caller
        else:
            inner.cancel()
            with pytest.raises(asyncio.CancelledError):
                await caller
    done: asyncio.Future[int] = loop.create_future()
    done.set_result(3)
    assert await shielded(done) == 3  # a done future: no wait


async def test_a_caller_that_gives_up_leaves_the_future_running_and_its_failure_seen(
    caplog: pytest.LogCaptureFixture,
) -> None:
    loop = asyncio.get_running_loop()
    inner: asyncio.Future[int] = loop.create_future()
    caller = asyncio.ensure_future(shielded(inner))
    await asyncio.sleep(0)
    caller.cancel()
    with pytest.raises(asyncio.CancelledError):
        await caller
    assert not inner.done()  # still running for whoever shares it
    inner.set_exception(RuntimeError("lost"))
    await asyncio.sleep(0)  # the callback reads the failure
    del inner
    gc.collect()
    assert "never retrieved" not in caplog.text


def test_running_loop_is_the_running_one_across_loops_and_refuses_outside() -> None:
    seen = [asyncio.run(_loop_pair()) for _ in range(2)]
    for cached, asked in seen:
        assert cached is asked  # the loop that runs now, not the last one's
    assert seen[0][0] is not seen[1][0]
    with pytest.raises(RuntimeError):
        running_loop()  # no loop runs: as asyncio.get_running_loop()


async def _loop_pair() -> tuple[asyncio.AbstractEventLoop, asyncio.AbstractEventLoop]:
    running_loop()
    return running_loop(), asyncio.get_running_loop()
