"""What a finished asyncio future ended with, read once: the helper every done callback shares.

asyncio logs "exception was never retrieved" for a failed future that is collected unread. A
task whose failure is told elsewhere (a run's outcome, a caller answered already) or matters to
nobody (a poll no one waits for) is read with :func:`failure`, as its done callback; code that
asks whether a finished future failed uses it too (it answers None for a cancelled one, where
``future.exception()`` would raise).
"""

from __future__ import annotations

import asyncio
from typing import Any


def failure(future: asyncio.Future[Any]) -> BaseException | None:
    """The exception ``future`` (done) ended with, now retrieved; None for a result or a
    cancellation. As a done callback, it keeps a failure nobody awaits out of asyncio's log."""
    return None if future.cancelled() else future.exception()
