"""A Thymio's clock: real time at a fixed control rate, one exchange with the robot per tick.

``tick()`` waits for the next period boundary, sends the commands that changed (motor targets,
lights), asks for the sensor variables and returns with them: the readings change only there
(and while idle). The clock is the host's wall clock (``time.time()`` at the readings), so that
members on one computer, or on computers kept in step by NTP, compare their times when a
``distributed_or`` is decided by who finished first.

Real time cannot be held back: ``hold(t)`` keeps the program's next ``tick()`` waiting, but the
robot drives on with its last command meanwhile (a ``distributed_or``'s loser stops a decision's
round trip after the winner, not on the same tick as in lock-step simulation). ``ticking()``
does nothing: the robot needs no ticks to go on. While idle (``idling()``) the motors are
stopped and a keeper polls the sensors each period, so that the readings stay current and a
robot that goes away is noticed idle too.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator, Awaitable, Callable

from mover._futures import failure
from robots.hal import HardwareLost, LostLatch, NoWorldAhead, sleep_in_ticks

from ._devices import Readings

__all__ = ["ThymioClock"]


class ThymioClock(LostLatch, NoWorldAhead):
    """``robots.hal.Clock`` over a Thymio (see the module docstring).

    ``exchange()`` is the hardware's: send the commands that changed, read the sensors, return
    the new readings; ``took(readings)`` feeds them to the devices; ``stop()`` stops the motors
    at once (as idling starts). :meth:`lose` is called when the link ends.
    """

    def __init__(
        self,
        tick_period: float,
        readings: Readings,
        exchange: Callable[[], Awaitable[Readings]],
        took: Callable[[Readings], None],
        stop: Callable[[], None],
    ) -> None:
        super().__init__()
        self.tick_period = tick_period
        self.readings = readings
        self._exchange = exchange
        self._took = took
        self._stop = stop
        self._task: asyncio.Future[Readings] | None = None
        self._next = time.monotonic()
        self._handed = -math.inf
        self._hold: float | None = None
        self._idle = False

    def now(self) -> float:
        """The wall-clock time of the current readings, in seconds."""
        return self.readings.t

    async def tick(self) -> None:
        """Wait for the next period, send the commands, take the new readings."""
        while True:
            self._check()
            if self._idle:
                raise RuntimeError("the Thymio is idle (inside clock.idling()): no ticks")
            if self._hold is None or self.now() <= self._hold:
                break
            await self._wait_change()
        if self._task is None:
            self._task = asyncio.ensure_future(self._paced())
            self._task.add_done_callback(failure)
        task = self._task
        try:
            await asyncio.shield(task)
        finally:
            if self._task is task and task.done():
                self._task = None
        if not task.cancelled() and failure(task) is None:
            self._take(task.result())

    async def _paced(self) -> Readings:
        delay = self._next - time.monotonic()
        if delay > 0:
            await asyncio.sleep(delay)
        self._next = max(self._next + self.tick_period, time.monotonic())
        self._handed = self.now()
        self._pulse()
        return await self._guard(self._exchange())

    def _take(self, readings: Readings) -> None:
        if readings.t > self.readings.t:
            self._took(readings)
            self.readings = readings
            self._pulse()

    async def sleep(self, dt: float) -> None:
        """Let ``dt`` seconds pass, ticking at the control rate."""
        await sleep_in_ticks(self, dt)

    def ticking(self) -> contextlib.AbstractAsyncContextManager[None]:
        """Nothing to do: a real robot goes on without ticks."""
        return contextlib.nullcontext()

    def hold(self, t: float | None) -> None:
        """The next ``tick()`` waits while the readings are later than ``t`` (see the module)."""
        self._hold = t
        self._pulse()

    async def passed(self, t: float) -> None:
        """Return once commands went in on readings of time ``t`` or later; HardwareLost if the
        robot goes away first."""
        while self._handed < t:
            self._check()
            await self._wait_change()

    @contextlib.asynccontextmanager
    async def idling(self) -> AsyncIterator[None]:
        """Motors stopped, no ticks, the readings kept current by a keeper (see the module)."""
        if self._idle:
            raise RuntimeError("the Thymio is already idle")
        task = self._task
        if task is not None:
            await asyncio.wait([task])  # the exchange under way ends first
        self._check()
        self._idle = True
        self._stop()
        self._pulse()
        keeper = asyncio.get_running_loop().create_task(self._keep())
        try:
            yield
        finally:
            keeper.cancel()
            await asyncio.gather(keeper, return_exceptions=True)
            self._idle = False
            self._pulse()

    async def _keep(self) -> None:
        with contextlib.suppress(HardwareLost):  # _guard noted it: waits raise it
            while True:
                self._take(await self._guard(self._exchange()))
                await asyncio.sleep(self.tick_period)
