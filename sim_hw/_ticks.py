"""A robot's clock over its link to the world: the readings, one exchange at a time, idling.

Shared by both wings' hardware (``sim_hw.continuous._hardware``, ``sim_hw.grid._hardware``);
the link itself (in process or over zenoh) is ``sim_hw._link``.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator, Awaitable, Callable

from mover._futures import failure
from robots.hal import HardwareLost

from ._link import WorldLink
from ._types import Command, Readings


class Ticks:
    """A robot's clock over a :class:`WorldLink`: its readings, one exchange at a time, idling.

    * ``tick(make)`` hands in ``make()`` (the command, built when the exchange starts) for the
      tick of the current readings and waits for the next readings. Concurrent callers share
      the exchange under way. The exchange runs as its own task: a caller that is cancelled
      leaves it to finish in the background (the world never sees half an exchange, and never
      a second command for the tick), and the next ``tick`` waits for it before its own.
    * ``idling(stop)``: the world neither waits for this robot nor lets it hold a tick back;
      ``stop()`` is the command that stands meanwhile (the stopped drive). The readings keep
      coming (frames carry idle robots' entries). Leaving is acknowledged by the world: on
      return, the world waits for this robot's command for the tick of ``readings``. A block
      left by cancellation does not wake the robot (it is going away); an exception does.
    * ``passed(t)`` returns once a command was handed in at a tick whose time is after ``t``.

    ``time_of(readings)`` is a tick's time (simulated seconds, or a round number); ``tick_of``
    its number; ``after(command, readings)`` runs when an exchange ends (in its task), before
    the new readings are seen.
    """

    def __init__(
        self,
        robot: str,
        link: WorldLink,
        readings: Readings,
        *,
        tick_of: Callable[[Readings], int],
        time_of: Callable[[Readings], float],
        after: Callable[[Command, Readings], None] | None = None,
    ) -> None:
        self.robot = robot
        self.readings = readings
        self._link = link
        self._tick_of, self._time_of, self._after = tick_of, time_of, after
        self._task: asyncio.Task[None] | None = None
        self._waiting = 0  # callers awaiting the exchange under way
        self._idle = False
        self._handed = -math.inf  # time of the readings the last command was handed in on
        self._hold: float | None = None  # no command on readings later than this (hold)
        self._lost: HardwareLost | None = None
        self._changed = asyncio.Event()

    @property
    def idle(self) -> bool:
        """Whether the robot is inside :meth:`idling`."""
        return self._idle

    def now(self) -> float:
        """The time of the current readings."""
        return self._time_of(self.readings)

    async def tick(self, make: Callable[[], Command]) -> None:
        """One exchange (shared with concurrent callers; see the class)."""
        if self._idle:
            raise RuntimeError(f"robot {self.robot!r} is idle (inside clock.idling()): no ticks")
        task = self._task
        if task is not None and not task.done() and self._waiting == 0:
            await self._finish(task)  # left by a cancelled caller: it goes first
            task = self._task
        while self._hold is not None and self.now() > self._hold and (task is None or task.done()):
            await self._wait_change()  # held (see hold): until released
            task = self._task
        if task is None or task.done():
            task = self._task = asyncio.get_running_loop().create_task(self._exchange(make))
            task.add_done_callback(failure)
        self._waiting += 1
        try:
            await asyncio.shield(task)
        finally:
            self._waiting -= 1

    async def _finish(self, task: asyncio.Task[None]) -> None:
        """Wait for ``task`` to end; raise what it raised if it lost the hardware."""
        await asyncio.wait([task])
        lost = failure(task)
        if isinstance(lost, HardwareLost):
            raise lost

    async def _exchange(self, make: Callable[[], Command]) -> None:
        if self._lost is not None:
            raise self._lost
        command = make()
        self._handed = self.now()
        self._pulse()
        try:
            readings = await self._link.exchange(self._tick_of(self.readings), command)
        except HardwareLost as exc:
            self._lose(exc)
            raise
        if self._after is not None:
            self._after(command, readings)
        self.readings = readings
        self._pulse()

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)``: a tick waits
        (and may be cancelled there, having handed in nothing). A ``distributed_or`` in
        simulated time holds a member that is past the earliest finish until the decision, so
        that a loser stops on the same tick whatever the wall clock does."""
        self._hold = t
        self._pulse()

    async def passed(self, t: float) -> None:
        """Return once a command was handed in with readings of time ``t`` or later: this
        robot went on past ``t`` (a robot whose program stopped at ``t`` hands in nothing)."""
        while not self._handed >= t:
            if self._lost is not None:
                raise self._lost
            await self._wait_change()

    @contextlib.asynccontextmanager
    async def idling(self, stop: Callable[[], Command]) -> AsyncIterator[None]:
        """Be idle for the block (see the class); HardwareLost if the world is gone."""
        if self._idle:
            raise RuntimeError(f"robot {self.robot!r} is already idle")
        if self._task is not None and not self._task.done():
            await self._finish(self._task)  # the exchange under way ends first
        if self._lost is not None:
            raise self._lost
        self._idle = True
        try:
            self.readings = await self._guard(self._link.idle(stop()))
            watch = asyncio.get_running_loop().create_task(self._watch())
            awake = True
            try:
                yield
            except asyncio.CancelledError:
                # Going away (the process ends, or reconnects): no wake. Should this robot
                # tick again, its first command wakes it in the world (see the door).
                awake = False
                raise
            finally:
                watch.cancel()
                await asyncio.gather(watch, return_exceptions=True)
                if awake and self._lost is None:
                    self.readings = await self._guard(self._link.wake())
        finally:
            self._idle = False
            self._pulse()

    async def _watch(self) -> None:
        def seen(readings: Readings) -> None:
            if self._tick_of(readings) > self._tick_of(self.readings):
                self.readings = readings

        with contextlib.suppress(HardwareLost):  # _guard noted it: passed() raises it
            await self._guard(self._link.watch(seen))

    async def _guard(self, call: Awaitable[Readings | None]) -> Readings:
        try:
            return await call
        except HardwareLost as exc:
            self._lose(exc)
            raise

    def _lose(self, exc: HardwareLost) -> None:
        if self._lost is None:
            self._lost = exc
        self._pulse()

    def _pulse(self) -> None:
        self._changed.set()
        self._changed = asyncio.Event()

    async def _wait_change(self) -> None:
        await self._changed.wait()
