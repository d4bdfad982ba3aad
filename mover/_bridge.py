"""The one door between zenoh's threads and asyncio.

Zenoh calls Python callbacks on its own threads. Every callback mover declares is made here:
it appends ``(handler, item)`` to a deque and, only when no wake-up is pending already, schedules
one with ``loop.call_soon_threadsafe``. The loop then drains the deque in a batch, so a burst of
messages costs one loop hop, not one per message (docs/transport.md: ~60-85 k msgs/s with a hop per
message, ~0.6 M with coalescing). A callback never blocks and never calls zenoh; the handlers run
on the loop, where every exception is logged and swallowed so that no bad message reaches the
loop's exception handler.

The deque is bounded, so that a loop held up while a flood comes in cannot grow without end:
past ``limit`` items or ``limit_bytes`` of payload, items of a *droppable* callback (broadcasts:
radio semantics) are dropped and counted; past twice that, every item is (calls, replies,
tokens: the overload is logged, once a second at most). A call so dropped ends for its caller
as unanswered.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections import deque
from collections.abc import Callable
from typing import Any, TypeVar

import zenoh

log = logging.getLogger("mover.bridge")

Handler = Callable[[Any], None]
T = TypeVar("T")

# Items drained per loop iteration before yielding to other tasks.
_BATCH = 4096
LIMIT = 10_000
"""Items waiting for the loop past which broadcasts are dropped (twice that: everything)."""
LIMIT_BYTES = 64 * 1024 * 1024
"""Payload bytes waiting for the loop past which broadcasts are dropped (twice: everything)."""


class Portal:
    """Hands items from zenoh threads to handlers running on one asyncio loop."""

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        *,
        limit: int = LIMIT,
        limit_bytes: int = LIMIT_BYTES,
    ) -> None:
        self._loop = loop
        self._items: deque[tuple[Handler, Any, int]] = deque()
        self._bytes = 0
        self.limit_bytes = limit_bytes
        self._pending = False
        self._closed = False
        self.limit = limit
        self.hops = 0  # loop wake-ups scheduled from threads (for benchmarks)
        self.dropped = 0  # broadcasts dropped because the loop fell behind
        self.overflowed = 0  # other items dropped because the loop fell far behind
        self._warned = 0.0

    def send(self, handler: Handler, item: Any, droppable: bool = False, size: int = 0) -> None:
        """Queue ``handler(item)`` (``size`` bytes) on the loop. Safe from any thread; never
        blocks."""
        if self._closed:
            return
        waiting, held = len(self._items), self._bytes
        behind = waiting >= self.limit or held >= self.limit_bytes
        if behind and (droppable or waiting >= 2 * self.limit or held >= 2 * self.limit_bytes):
            if droppable:
                self.dropped += 1
                return
            self.overflowed += 1
            now = time.monotonic()
            if now - self._warned > 1.0:
                self._warned = now
                log.warning(
                    "the loop is %d items behind: dropping (%d so far)", waiting, self.overflowed
                )
            return
        self._bytes += size
        self._items.append((handler, item, size))
        if not self._pending:
            self._pending = True
            self.hops += 1
            try:
                self._loop.call_soon_threadsafe(self._drain)
            except RuntimeError:  # the loop is closed: the node is going away
                self._closed = True

    def _drain(self) -> None:
        self._pending = False
        items = self._items
        for _ in range(min(len(items), _BATCH)):
            handler, item, size = items.popleft()
            self._bytes -= size
            try:
                handler(item)
            except Exception:
                log.exception("handler %s failed on an incoming item", handler)
        if items and not self._pending:
            self._pending = True
            self._loop.call_soon(self._drain)

    def callback(
        self,
        handler: Callable[[T], None],
        on_close: Callable[[None], None] | None = None,
        *,
        droppable: bool = False,
        size: Callable[[T], int] | None = None,
    ) -> zenoh.handlers.Callback[T]:
        """A zenoh callback handler that sends each item to ``handler`` on the loop.

        ``on_close`` (called on the loop with ``None``) runs when zenoh drops the callback: for a
        get, when the query is finished (every reply in, or timed out). ``droppable`` items go
        first when the loop falls behind; ``size(item)`` is an item's payload size in bytes
        (see the module).
        """
        send = self.send

        def on_item(item: T) -> None:
            send(handler, item, droppable, size(item) if size is not None else 0)

        if on_close is None:
            return zenoh.handlers.Callback(on_item, indirect=False)
        return zenoh.handlers.Callback(on_item, lambda: send(on_close, None), indirect=False)

    def close(self) -> None:
        """Stop accepting items; items already queued are dropped."""
        self._closed = True
        self._items.clear()
        self._bytes = 0


async def run_blocking(fn: Callable[[], Any]) -> Any:
    """Run a blocking zenoh call (open, close) on a thread of its own, joined before returning.

    Unlike ``asyncio.to_thread`` this leaves no executor thread behind after the node closes.
    """
    import threading

    loop = asyncio.get_running_loop()
    future: asyncio.Future[Any] = loop.create_future()

    def settle(outcome: tuple[bool, Any]) -> None:
        if future.done():
            return
        ok, value = outcome
        if ok:
            future.set_result(value)
        else:
            future.set_exception(value)

    def work() -> None:
        try:
            outcome: tuple[bool, Any] = (True, fn())
        except BaseException as exc:
            outcome = (False, exc)
        with contextlib.suppress(RuntimeError):  # the loop is gone
            loop.call_soon_threadsafe(settle, outcome)

    thread = threading.Thread(target=work, name="mover-blocking", daemon=True)
    thread.start()
    try:
        return await future
    finally:
        thread.join(timeout=10)


def sample_size(sample: zenoh.Sample | zenoh.Query) -> int:
    """A sample's or a query's payload size (for :meth:`Portal.callback`)."""
    payload = sample.payload
    return len(payload) if payload is not None else 0
