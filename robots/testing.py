"""Fakes of the hardware (``robots.hal``) for testing a behaviour without a world.

A behaviour written against the HAL runs unchanged on these: a clock that ticks when told, a
drive that records its commands, odometry that integrates them, a sonar whose ranges a test
sets. ``fake_hardware()`` builds a :class:`robots.hal.Hardware` of them::

    clock, sonar = FakeClock(tick_period=0.1), FakeSonar(readings=(0.2, 2.0, 2.0))
    hw = fake_hardware("ada", clock=clock, sonar=sonar)
    await my_behaviour(hw)          # it ticks; the odometry follows its drive
    assert clock.now() == pytest.approx(1.0)

The clock implements ``robots.hal.Clock`` (and so ``mover.IdleClock``) the way a lock-step
world does, within one process: ``tick()`` hands in the commands and advances one period,
``hold(t)`` keeps it from going past ``t``, ``passed(t)`` waits until a command went in on
readings of ``t`` or later, ``idling()`` stops the drive and forbids ticks, and ``lose()`` makes
the hardware go away (``HardwareLost``). The grid HAL (``robots.grid_hal``) has no fakes here:
its tests run the grid world in-process, which is as cheap.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field

from .hal import Hardware, HardwareLost, Pose, sleep_in_ticks

__all__ = ["FakeClock", "FakeDrive", "FakeOdometry", "FakeSonar", "fake_hardware"]


class FakeClock:
    """Hardware time that advances one ``tick_period`` per ``tick()`` (``robots.hal.Clock``).

    ``on_tick`` callbacks run after each tick (``fake_hardware`` moves the odometry there);
    ``on_idle`` ones as an idle block begins (it stops the drive). ``ticks`` counts the ticks,
    ``idle`` says whether an ``idling()`` block is under way, ``held`` is the ``hold`` time.
    """

    def __init__(self, tick_period: float = 0.1, start: float = 0.0) -> None:
        self.tick_period = tick_period
        self.start = start
        self.ticks = 0
        self.idle = False
        self.held: float | None = None
        self.handed_at = -math.inf  # the time of the readings the last command went in on
        self.on_tick: list[Callable[[], None]] = []
        self.on_idle: list[Callable[[], None]] = []
        self._lost: HardwareLost | None = None
        self._changed = asyncio.Condition()

    def now(self) -> float:
        """Hardware time in seconds: ``start`` plus the ticks so far."""
        return self.start + self.ticks * self.tick_period

    async def tick(self) -> None:
        """Hand in the commands on this tick's readings and advance one period (waiting while
        held at an earlier time). RuntimeError inside ``idling()``; HardwareLost once lost."""
        if self.idle:
            raise RuntimeError("no ticks while idling")
        async with self._changed:
            await self._changed.wait_for(lambda: self._lost is not None or not self._held())
            self._check()
            self.handed_at = self.now()
            self.ticks += 1
            self._changed.notify_all()
        for hook in self.on_tick:
            hook()
        await asyncio.sleep(0)  # a tick is never instant: the other tasks run meanwhile

    async def sleep(self, dt: float) -> None:
        """Let ``dt`` seconds pass: whole ticks, at least one."""
        await sleep_in_ticks(self, dt)

    @contextlib.asynccontextmanager
    async def ticking(self) -> AsyncIterator[None]:
        """Nothing to do: no world waits for this clock."""
        yield

    @contextlib.asynccontextmanager
    async def idling(self) -> AsyncIterator[None]:
        """Be idle for the block: ``on_idle`` runs (the drive stops), ticks are refused."""
        self._check()
        self.idle = True
        for hook in self.on_idle:
            hook()
        try:
            yield
        finally:
            self.idle = False

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)``."""
        self.held = t
        self._notify()

    async def passed(self, t: float) -> None:
        """Return once a command went in on readings of time ``t`` or later."""
        async with self._changed:
            await self._changed.wait_for(lambda: self._lost is not None or self.handed_at >= t)
            if self.handed_at < t:
                self._check()

    def lose(self, error: HardwareLost | None = None) -> None:
        """The hardware goes away: ticks, ``passed`` and ``idling`` raise ``error`` from now."""
        self._lost = error or HardwareLost("the fake hardware was lost")
        self._notify()

    def _held(self) -> bool:
        return self.held is not None and self.now() > self.held

    def _check(self) -> None:
        if self._lost is not None:
            raise self._lost

    def _notify(self) -> None:
        async def wake() -> None:
            async with self._changed:
                self._changed.notify_all()

        with contextlib.suppress(RuntimeError):  # no loop: nobody can be waiting
            asyncio.get_running_loop().create_task(wake())


@dataclass
class FakeDrive:
    """A differential drive that records its commands (``robots.hal.Drive``)."""

    max_speed: float = 0.3
    v: float = 0.0
    omega: float = 0.0
    commands: list[tuple[float, float]] = field(default_factory=list)

    def set_velocity(self, v: float, omega: float) -> None:
        """Drive at ``v`` m/s turning at ``omega`` rad/s (recorded in ``commands``)."""
        self.v, self.omega = v, omega
        self.commands.append((v, omega))

    def stop(self) -> None:
        """Stop both wheels."""
        self.set_velocity(0.0, 0.0)


@dataclass
class FakeOdometry:
    """Dead reckoning without drift (``robots.hal.Odometry``): ``pose`` is set, or moved by
    :meth:`follow` (which ``fake_hardware`` calls every tick)."""

    now: Pose = (0.0, 0.0, 0.0)

    def pose(self) -> Pose:
        """The (x, y, heading)."""
        return self.now

    def follow(self, drive: FakeDrive, dt: float) -> None:
        """Move as ``drive`` would in ``dt`` seconds (a unicycle, heading in (-π, π])."""
        x, y, h = self.now
        x, y = x + drive.v * math.cos(h) * dt, y + drive.v * math.sin(h) * dt
        h = math.atan2(math.sin(h + drive.omega * dt), math.cos(h + drive.omega * dt))
        self.now = (x, y, h)


@dataclass
class FakeSonar:
    """A ring of range sensors that reads what the test sets (``robots.hal.Sonar``); all rays
    read ``max_range`` (nothing near) unless ``readings`` says otherwise."""

    angles: tuple[float, ...] = (0.0, math.pi / 4, -math.pi / 4)
    max_range: float = 2.0
    readings: tuple[float, ...] | None = None

    def ranges(self) -> tuple[float, ...]:
        """The set ``readings``, else ``max_range`` on every ray."""
        return self.readings if self.readings is not None else (self.max_range,) * len(self.angles)


def fake_hardware(
    id: str = "robot",
    *,
    clock: FakeClock | None = None,
    drive: FakeDrive | None = None,
    odometry: FakeOdometry | None = None,
    sonar: FakeSonar | None = None,
) -> Hardware:
    """A :class:`robots.hal.Hardware` of fakes (new ones where none is given): each tick moves
    the odometry as the drive commands, and an idle block stops the drive. Pass the fakes a
    test wants to steer or read."""
    clock = clock or FakeClock()
    drive = drive or FakeDrive()
    odometry = odometry or FakeOdometry()
    clock.on_tick.append(lambda: odometry.follow(drive, clock.tick_period))
    clock.on_idle.append(drive.stop)
    return Hardware(id=id, clock=clock, drive=drive, odometry=odometry, sonar=sonar or FakeSonar())
