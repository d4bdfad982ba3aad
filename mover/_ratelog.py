"""A log that an outsider cannot flood: one line per cause per interval, with a count.

Whatever a stranger on the network can make a node notice (fake liveliness tokens, junk
answers to its questions) is logged here rather than line by line. The first fault of a cause
is logged at once; the ones that follow within ``interval`` seconds are only counted, and when
the interval ends one line says how many there were (with the last of them), which opens the
next interval. A cause that stays quiet for a whole interval is forgotten, so its next fault is
logged at once again. Measured: 2000 fake tokens under a team's prefix wrote 2000 WARNING lines
into every member's log before, 1 line (and a count 10 s later) with this.

Causes are fixed strings chosen by the code ("tokens", "hello"), never a name an outsider picks;
even so, past :data:`MAX_CAUSES` the rest share one.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import KW_ONLY, dataclass, field

MAX_CAUSES = 64

Schedule = Callable[[float, Callable[[], None]], object]
"""``schedule(delay, callback)``: call ``callback()`` after ``delay`` seconds (on the loop)."""


def _on_loop(delay: float, callback: Callable[[], None]) -> object:
    return asyncio.get_running_loop().call_later(delay, callback)


@dataclass
class _Window:
    opened: float
    count: int = 0  # faults counted (not logged) since the window opened
    last: str = ""


@dataclass
class RateLog:
    """One WARNING line per cause per ``interval`` seconds, with a count (see the module):
    ``owner`` begins each line; ``clock`` and ``schedule`` are the loop's unless a test's."""

    owner: str
    logger: logging.Logger
    _: KW_ONLY
    interval: float = 10.0
    clock: Callable[[], float] = time.monotonic
    schedule: Schedule = _on_loop
    counts: dict[str, int] = field(default_factory=dict)
    """Every fault seen, by cause (logged or not)."""
    _windows: dict[str, _Window] = field(default_factory=dict)

    def warn(self, cause: str, message: str) -> None:
        """A fault of ``cause``: logged now if it is the first of an interval, else counted."""
        if cause not in self._windows and len(self._windows) >= MAX_CAUSES:
            cause = "(others)"
        self.counts[cause] = self.counts.get(cause, 0) + 1
        window = self._windows.get(cause)
        if window is not None:
            window.count += 1
            window.last = message
            return
        self._windows[cause] = _Window(self.clock())
        self.logger.warning("%s: %s", self.owner, message)
        self.schedule(self.interval, lambda: self._close(cause))

    def _close(self, cause: str) -> None:
        """The interval of ``cause`` ended: say how many were counted, or forget the cause."""
        window = self._windows.pop(cause, None)
        if window is None or window.count == 0:
            return
        took = self.clock() - window.opened
        more = f"(and {window.count} more like it in the last {took:.0f} s)"
        self.logger.warning("%s: %s %s", self.owner, window.last, more)
        self._windows[cause] = _Window(self.clock())
        self.schedule(self.interval, lambda: self._close(cause))
