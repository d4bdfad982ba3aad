"""The run's clock, and a member's OR operation timed by it.

:class:`RunClock` is what a host's hardware offers a run for reproducible steps: the one clock
protocol (:class:`mover.IdleClock`: now, passed, hold, idling) plus ``engage``/``release``, which
the host calls as runs start and end. :class:`TimedOp` is a member's operation in an OR decided
in simulated time, which the designated member's ``or_passed`` questions wait on. Without a
clock neither is used, and an OR costs only its wall-clock messages.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Awaitable, Callable
from typing import Any, Protocol

from .._clock import IdleClock
from .._futures import failure
from ._group import Settled

Spawn = Callable[[Awaitable[Any]], "asyncio.Task[Settled]"]


class RunClock(IdleClock, Protocol):
    """What a host's hardware offers for reproducible runs: its simulated time.

    ``ProgramHost.clock`` is one (or None: a workstation, or no hardware yet); the robot process
    sets it as an adapter over its hardware's clock and its idle task. A run engages it when it
    starts and releases it when the last run on the host ends; a ``distributed_and`` idles it
    (``idling``) while it waits for the other members.
    """

    async def engage(self) -> None:
        """Stop idling: on return the world waits for this robot's commands."""
        ...

    def release(self) -> None:
        """No run drives the hardware any more: idle again."""
        ...


def hold_here(clock: RunClock) -> None:
    """Hold ``clock`` where it is: nothing more is handed in on its current readings (nor
    later ones) until ``clock.hold(None)``. A member whose operation in a step ended is held so
    until the step is over, so that where it stops is fixed in simulated time even if the
    program keeps a background ``ticking()``."""
    clock.hold(math.nextafter(clock.now(), -math.inf))


class TimedOp:
    """This member's operation in an OR step decided in simulated time, for the designated
    member's ``or_passed``; it runs as a task of its step (``spawn``), and settles
    (:class:`Settled`) rather than raise."""

    def __init__(
        self, clock: RunClock, operation: Callable[[], Awaitable[Any]], spawn: Spawn
    ) -> None:
        self.clock = clock
        self.finished_at: float | None = None  # simulated time the operation returned at
        self.op: asyncio.Task[Settled] = spawn(self._run(operation))

    async def _run(self, operation: Callable[[], Awaitable[Any]]) -> Any:
        result = await operation()
        self.finished_at = self.clock.now()  # as it returns: no loop turn in between
        hold_here(self.clock)  # while the decision travels
        return result

    async def passed(self, t: float) -> dict[str, Any]:
        """Once the operation finished or the clock passed ``t`` as far as it surely can
        (``clock.reach(t)``: a loser stops there whatever the scheduling): which (see
        or_passed)."""
        t = self.clock.reach(t)
        if self.finished_at is None and not self.op.done():
            waiter = asyncio.ensure_future(self.clock.passed(t))
            try:
                await asyncio.wait({self.op, waiter}, return_when=asyncio.FIRST_COMPLETED)
            finally:
                waiter.cancel()
                await asyncio.gather(waiter, return_exceptions=True)
            lost = waiter.done() and failure(waiter) is not None
            if lost and self.finished_at is None:
                return {"out": True}  # the hardware went away: this run will not claim
            for _ in range(3):  # an operation the same readings ended returns first
                if self.finished_at is not None or self.op.done():
                    break
                await asyncio.sleep(0)
        if self.finished_at is not None:
            return {"finished": self.finished_at}
        if self.op.done():
            return {"out": True}  # failed or cancelled: it will never claim
        self.clock.hold(t)  # no further until decided: where a loser stops is then fixed
        return {"passed": self.clock.now()}
