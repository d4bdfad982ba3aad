"""A robot's clock over its link to the world: the readings, one exchange at a time, idling.

Shared by both wings' hardware (``sim_hw.continuous._hardware``, ``sim_hw.grid._hardware``);
the link itself (in process or over zenoh) is ``sim_hw._link``.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator, Callable

from mover._futures import failure, running_loop, shielded
from robots.hal import HardwareLost, LostLatch

from ._link import DoorLink, WorldLink
from ._types import Command, Readings


class Ticks(LostLatch):
    """A robot's clock over a :class:`WorldLink`: its readings, one exchange at a time, idling.

    * ``tick(make)`` hands in ``make()`` (the command, built when the exchange starts) for the
      tick of the current readings and waits for the next readings. Concurrent callers share
      the exchange under way. The exchange runs as its own task (or, in the world's own
      process, is the door's future of the readings, the command handed in at once): a caller
      that is cancelled leaves it to finish in the background (the world never sees half an
      exchange, and never a second command for the tick), and the next ``tick`` takes its
      readings as its own (the tick's command went in already).
    * The readings change only inside a call of this robot's (``tick``, or leaving
      ``idling``), never when the world happens to answer: after a caller was cancelled the
      readings stay those it handed its command in on until the next ``tick``. So what a
      program reads next is fixed in simulated time (a ``distributed_or``'s losers, cancelled
      inside a tick, read the same whether or not the world answered meanwhile).
    * ``idling(stop)``: the world neither waits for this robot nor lets it hold a tick back;
      ``stop()`` is the command that stands meanwhile (the stopped drive). The readings keep
      coming (frames carry idle robots' entries). Leaving is acknowledged by the world: on
      return, the world waits for this robot's command for the tick of ``readings``. A block
      left by cancellation does not wake the robot (it is going away); an exception does.
    * ``passed(t)`` returns once a command was handed in at a tick whose time is after ``t``.
    * ``reach(t)``: how far past ``t`` the robot surely gets, the world's control delay
      (``link.lead`` ticks of ``period``) on: a time between the ticks K - 1 and K after ``t``'s,
      half a tick from either so that float times compare exactly.

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
        period: float,
        after: Callable[[Command, Readings], None] | None = None,
    ) -> None:
        super().__init__()
        self.robot = robot
        self.readings = readings
        self._link = link
        self._tick_of, self._time_of, self._after = tick_of, time_of, after
        self._period = period
        self._door = link if isinstance(link, DoorLink) else None  # (see submit there)
        self._task: asyncio.Future[Readings] | None = None  # the last exchange started
        self._command: Command = {}  # its command
        self._exchanges = 0  # exchanges started (the last one's number)
        self._taken = 0  # the last exchange whose readings are in (see take)
        self._idle = False
        self._handed = -math.inf  # time of the readings the last command was handed in on
        self._hold: float | None = None  # no command on readings later than this (hold)

    @property
    def idle(self) -> bool:
        """Whether the robot is inside :meth:`idling`."""
        return self._idle

    def now(self) -> float:
        """The time of the current readings."""
        return self._time_of(self.readings)

    @property
    def held(self) -> bool:
        """Whether a tick would wait for a hold to be lifted now (see :meth:`hold`)."""
        return self._hold is not None and self.now() > self._hold and self._taken_all()

    async def tick(self, make: Callable[[], Command]) -> None:
        """One exchange (shared with concurrent callers; see the class); RuntimeError inside
        ``idling()``."""
        while True:
            if self._idle:
                raise RuntimeError(
                    f"robot {self.robot!r} is idle (inside clock.idling()): no ticks"
                )
            if not self.held:
                break
            await self._wait_change()  # held (see hold): until released
        task = self._task
        if task is None or self._taken_all():
            task = self._begin(make)
            if task.done():  # this command completed the tick: still give others a turn
                await asyncio.sleep(0)
        await shielded(task)  # (which also takes a failure's exception as seen)
        self._take(task)

    def _begin(self, make: Callable[[], Command]) -> asyncio.Future[Readings]:
        """Start the next exchange: hand in ``make()`` for the tick of the readings."""
        self._check()
        command = self._command = make()
        self._exchanges += 1
        self._handed = self.now()
        self._pulse()
        tick = self._tick_of(self.readings)
        task: asyncio.Future[Readings]
        if self._door is None:
            task = running_loop().create_task(self._exchange(tick, command))
            task.add_done_callback(failure)
        else:
            try:
                task = self._door.submit(tick, command)
            except HardwareLost as exc:
                self.lose(exc)
                task = asyncio.get_running_loop().create_future()
                task.set_exception(exc)
                task.add_done_callback(failure)  # (seen even if no caller awaits it)
        self._task = task
        return task

    async def changed(self) -> None:
        """Return at the next change: readings taken, a command handed in, a hold, idling
        entered or left, :meth:`poke`."""
        await self._wait_change()

    def poke(self) -> None:
        """Wake whoever waits in :meth:`changed`."""
        self._pulse()

    def _taken_all(self) -> bool:
        """Whether the readings of every exchange started are in (none is under way or left;
        one that failed or was cancelled has none to take)."""
        task = self._task
        if task is not None and task.done() and (task.cancelled() or failure(task) is not None):
            self._taken = self._exchanges
        return self._taken == self._exchanges

    def _take(self, task: asyncio.Future[Readings]) -> None:
        """Take the readings of ``task``, an exchange that ended well, unless they are in
        already (callers that shared it take them once; an exchange is begun only once the
        readings of the one before are in)."""
        readings = task.result()
        if task is self._task and self._taken < self._exchanges:
            self._taken = self._exchanges
            if self._after is not None:
                self._after(self._command, readings)
            self.readings = readings
            self._pulse()

    async def _finish(self) -> None:
        """Let the exchange under way end and take its readings (as a caller that was cancelled
        would have); raise what it raised if it lost the hardware."""
        while not self._taken_all():  # (another caller may start one meanwhile)
            task = self._task
            assert task is not None
            await asyncio.wait([task])
            lost = failure(task)
            if isinstance(lost, HardwareLost):
                raise lost
            if lost is None and not task.cancelled():
                self._take(task)

    async def _exchange(self, tick: int, command: Command) -> Readings:
        return await self._guard(self._link.exchange(tick, command))

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)``: a tick waits
        (and may be cancelled there, having handed in nothing). A ``distributed_or`` in
        simulated time holds a member that is past the earliest finish until the decision, so
        that a loser stops on the same tick whatever the wall clock does."""
        self._hold = t
        self._pulse()

    def reach(self, t: float) -> float:
        """``t``, or with a control delay of K ticks ``t`` + (K - 1/2) ticks (see the class):
        while a robot that finished at ``t`` holds, the world runs up to K ticks past it, and
        a robot that waits until it ``passed`` there has the same readings however the wall
        clock went."""
        lead = self._link.lead
        return t + (lead - 0.5) * self._period if lead else t

    async def passed(self, t: float) -> None:
        """Return once a command was handed in with readings of time ``t`` or later: this
        robot went on past ``t`` (a robot whose program stopped at ``t`` hands in nothing)."""
        while not self._handed >= t:
            self._check()
            await self._wait_change()

    @contextlib.asynccontextmanager
    async def idling(self, stop: Callable[[], Command]) -> AsyncIterator[None]:
        """Be idle for the block (see the class); HardwareLost if the world is gone."""
        if self._idle:
            raise RuntimeError(f"robot {self.robot!r} is already idle")
        await self._finish()  # the exchange under way ends first
        self._check()
        self._idle = True  # (no await since _finish: no exchange can start in between)
        self._pulse()
        try:
            at = self._tick_of(self.readings)  # the ticks before: commands handed in
            self.readings = await self._guard(self._link.idle(stop(), at))
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
