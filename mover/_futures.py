"""What a finished asyncio future ended with, read once: the helper every done callback shares.

asyncio logs "exception was never retrieved" for a failed future that is collected unread. A
task whose failure is told elsewhere (a run's outcome, a caller answered already) or matters to
nobody (a poll no one waits for) is read with :func:`failure`, as its done callback; code that
asks whether a finished future failed uses it too (it answers None for a cancelled one, where
``future.exception()`` would raise).
"""

from __future__ import annotations

import asyncio
import os
import threading
from typing import Any, TypeVar

_T = TypeVar("_T")


def failure(future: asyncio.Future[Any]) -> BaseException | None:
    """The exception ``future`` (done) ended with, now retrieved; None for a result or a
    cancellation. As a done callback, it keeps a failure nobody awaits out of asyncio's log."""
    return None if future.cancelled() else future.exception()


async def shielded(inner: asyncio.Future[_T]) -> _T:
    """``await asyncio.shield(inner)`` for a future, with one callback through the loop fewer.

    The caller gets what ``inner`` ends with (its result, its exception, or CancelledError if
    it was cancelled); a caller that is cancelled meanwhile leaves ``inner`` running, and a
    failure it then ends with counts as seen (as ``asyncio.shield`` does). ``asyncio.shield``
    passes the outcome through a second future and two more callbacks: three callbacks run by
    the loop where this runs two (a robot's clock awaits one such future a tick).
    """
    if not inner.done():
        waiter: asyncio.Future[None] = inner.get_loop().create_future()

        def wake(done: asyncio.Future[_T]) -> None:
            if waiter.cancelled():  # the caller gave up: nobody reads this outcome
                failure(done)
            elif not waiter.done():
                waiter.set_result(None)

        inner.add_done_callback(wake)
        try:
            await waiter
        except asyncio.CancelledError:
            if inner.done():  # it ended as the caller gave up: its outcome is seen here
                failure(inner)
            raise
    return inner.result()


class _Running(threading.local):
    loop: asyncio.AbstractEventLoop | None = None


_running = _Running()
os.register_at_fork(after_in_child=lambda: setattr(_running, "loop", None))


def running_loop() -> asyncio.AbstractEventLoop:
    """``asyncio.get_running_loop()`` for the hot paths (a tick's futures, a message's wake-up).

    In CPython 3.11 every ``get_running_loop`` makes a ``getpid`` system call (to notice a
    forked child using its parent's loop): ~5 % of a tick of 200 robots in process. This keeps
    the thread's running loop and asks asyncio only when it stopped running (a forked child
    forgets it).
    """
    loop = _running.loop
    if loop is None or not loop.is_running():
        loop = _running.loop = asyncio.get_running_loop()
    return loop
