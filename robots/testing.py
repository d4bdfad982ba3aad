"""Fakes of the hardware (``robots.hal``, ``robots.grid_hal``) for testing a behaviour without
a world.

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
the hardware go away (``HardwareLost``).

The grid HAL has its fakes too: :class:`FakeRoundClock` (a ``robots.grid_hal.RoundClock``: the
same clock in whole rounds, with the observer's end and ``owned``), a drive, odometry, senses,
a floor cell, a gripper and a radio. ``fake_grid_hardware()`` builds a
:class:`robots.grid_hal.GridHardware` of them, in which each round's end applies what the
robot asked (the move unless ``blocked``, the floor's writes, the gripper's pick and drop)::

    clock, senses = FakeRoundClock(end=5), FakeGridSenses(cell=Here(-1, 0, 100, False))
    hw = fake_grid_hardware("ant", clock=clock, senses=senses)
    hw.drive.move(EAST)
    await hw.clock.tick()
    assert hw.odometry.pose() == (0.0, 1.0, 0.0) and hw.drive.moved()
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field

from .grid_hal import FREE, OFFSETS, GridHardware, Here, Near, Seen
from .hal import Hardware, HardwareLost, NoWorldAhead, Pose, sleep_in_ticks

__all__ = [
    "FakeClock",
    "FakeDrive",
    "FakeGridDrive",
    "FakeGridFloor",
    "FakeGridGripper",
    "FakeGridOdometry",
    "FakeGridRadio",
    "FakeGridSenses",
    "FakeOdometry",
    "FakeRoundClock",
    "FakeSonar",
    "fake_grid_hardware",
    "fake_hardware",
]


class _Ticking(NoWorldAhead):
    """What the fake clocks share: ticks that wait while held, their hooks, ``hold``,
    ``passed``, ``idling`` and a lost hardware. The time (``now``) is each clock's own.

    ``on_tick`` callbacks run after each tick (the fake hardware moves the robot there);
    ``on_idle`` ones as an idle block begins (it stops the drive). ``ticks`` counts the ticks,
    ``idle`` says whether an ``idling()`` block is under way, ``held`` is the ``hold`` time.
    """

    def __init__(self) -> None:
        self.ticks = 0
        self.idle = False
        self.held: float | None = None
        self.handed_at = -math.inf  # the time of the readings the last command went in on
        self.on_tick: list[Callable[[], None]] = []
        self.on_idle: list[Callable[[], None]] = []
        self._lost: HardwareLost | None = None
        self._changed = asyncio.Condition()

    def now(self) -> float:
        """The time of the current readings."""
        raise NotImplementedError

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


class FakeClock(_Ticking):
    """Hardware time that advances one ``tick_period`` per ``tick()`` (``robots.hal.Clock``).

    ``on_tick`` callbacks run after each tick (``fake_hardware`` moves the odometry there);
    ``on_idle`` ones as an idle block begins (it stops the drive). ``ticks`` counts the ticks,
    ``idle`` says whether an ``idling()`` block is under way, ``held`` is the ``hold`` time.
    """

    def __init__(self, tick_period: float = 0.1, start: float = 0.0) -> None:
        super().__init__()
        self.tick_period = tick_period
        self.start = start

    def now(self) -> float:
        """Hardware time in seconds: ``start`` plus the ticks so far."""
        return self.start + self.ticks * self.tick_period

    async def sleep(self, dt: float) -> None:
        """Let ``dt`` seconds pass: whole ticks, at least one."""
        await sleep_in_ticks(self, dt)

    @contextlib.asynccontextmanager
    async def ticking(self) -> AsyncIterator[None]:
        """Nothing to do: no world waits for this clock."""
        yield


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


# -- the grid HAL ------------------------------------------------------------------------------


class FakeRoundClock(_Ticking):
    """Rounds of a grid world (``robots.grid_hal.RoundClock``): one round per ``tick()``.

    Ticks, hooks, ``hold``, ``passed``, ``idling`` and ``lose`` as :class:`FakeClock`'s, in
    rounds. The world's observer ends the run at round ``end`` (None: never; a test may set it
    at any time). ``owned(at)`` ticks the clock to round ``at`` itself (the hooks run: a robot
    that asked nothing stays), then lets the block drive it.
    """

    def __init__(self, start: int = 0, end: int | None = None) -> None:
        super().__init__()
        self.start = start
        self.end = end
        self.owner = False  # whether an owned() block is under way

    def now(self) -> int:
        """The round of the current perception: ``start`` plus the ticks so far."""
        return self.start + self.ticks

    def ended(self) -> bool:
        """Whether the observer ended the run (round ``end`` is reached)."""
        return self.end is not None and self.now() >= self.end

    @contextlib.asynccontextmanager
    async def owned(self, at: int) -> AsyncIterator[None]:
        """Drive the rounds from round ``at``; RuntimeError if it has passed, or if the clock is
        owned already."""
        if self.owner:
            raise RuntimeError("the clock is already owned")
        if self.now() > at:
            raise RuntimeError(f"round {at} had already passed (now {self.now()})")
        self.owner = True
        try:
            while self.now() < at:
                await self.tick()
            yield
        finally:
            self.owner = False


@dataclass
class FakeGridDrive:
    """One-cell moves that record their commands (``robots.grid_hal.GridDrive``).

    A move asked in a round happens at the round's end (:meth:`settle`, which
    ``fake_grid_hardware`` calls every tick) unless ``blocked`` holds its direction.
    """

    blocked: set[int] = field(default_factory=set)
    commands: list[int | None] = field(default_factory=list)
    direction: int | None = None  # the move asked for this round (None: stay)
    went: bool = False  # whether the last round's move happened

    def move(self, direction: int | None) -> None:
        """Move one cell in ``direction`` at this round's end (recorded in ``commands``)."""
        self.direction = direction
        self.commands.append(direction)

    def stop(self) -> None:
        """Stay this round."""
        self.move(None)

    def moved(self) -> bool:
        """Whether the last round's move happened."""
        return self.went

    def settle(self) -> int | None:
        """The round ends: the direction moved in (None: the robot stayed or was blocked)."""
        direction, self.direction = self.direction, None
        self.went = direction is not None and direction not in self.blocked
        return direction if self.went else None


@dataclass
class FakeGridOdometry:
    """Cells moved since the start (``robots.grid_hal.GridOdometry``): ``cell`` is set, or
    moved by :meth:`follow` (which ``fake_grid_hardware`` calls every tick)."""

    cell: tuple[int, int] = (0, 0)  # (d_row, d_col)

    def pose(self) -> tuple[float, float, float]:
        """(d_row, d_col, 0.0) from the start cell."""
        return (float(self.cell[0]), float(self.cell[1]), 0.0)

    def follow(self, direction: int | None) -> None:
        """Move one cell in ``direction`` (None: stay)."""
        if direction is not None:
            dr, dc = OFFSETS[direction]
            self.cell = (self.cell[0] + dr, self.cell[1] + dc)


_UNMARKED = Here(-1, 0, 0, False)
_FOUR_FREE = tuple(Near(d, FREE, -1, 0, 0, False) for d in range(4))


@dataclass
class FakeGridSenses:
    """What the robot perceives, as the test sets it (``robots.grid_hal.GridSenses``): the
    ``cell`` under it, its ``near`` neighbours (four free, unmarked ones unless set), the cells
    ``seen`` along its view rays, and the nest ``heading``."""

    cell: Here = _UNMARKED
    near: tuple[Near, ...] = _FOUR_FREE
    seen: tuple[Seen, ...] = ()
    heading: tuple[float, float] = (0.0, 0.0)

    def here(self) -> Here:
        """The cell under the robot."""
        return self.cell

    def around(self) -> tuple[Near, ...]:
        """The neighbouring cells."""
        return self.near

    def rays(self) -> tuple[Seen, ...]:
        """The cells seen along the view rays."""
        return self.seen

    def compass(self) -> tuple[float, float]:
        """The unit (d_row, d_col) toward the base."""
        return self.heading


@dataclass
class FakeGridFloor:
    """The floor cell under the robot (``robots.grid_hal.GridFloor``): ``value`` and ``colour``
    as the test sets them; a write takes effect at the round's end (:meth:`settle`) and shows
    in :meth:`read` at once; scent adds up in ``pheromone``. ``writes`` records the writes."""

    value: int = -1
    colour: int = 0
    pheromone: float = 0.0
    writes: list[tuple[int | None, int | None]] = field(default_factory=list)
    pending: tuple[int | None, int | None, float] = (None, None, 0.0)  # value, colour, scent

    def read(self) -> tuple[int, int]:
        """(value, colour), a pending write included."""
        value, colour, _ = self.pending
        return (self.value if value is None else value, self.colour if colour is None else colour)

    def write(self, value: int | None = None, colour: int | None = None) -> None:
        """Write the cell at this round's end (None: leave as is)."""
        old_value, old_colour, scent = self.pending
        self.pending = (
            old_value if value is None else value,
            old_colour if colour is None else colour,
            scent,
        )
        self.writes.append((value, colour))

    def scent(self, amount: float) -> None:
        """Add pheromone at this round's end."""
        value, colour, scent = self.pending
        self.pending = (value, colour, scent + amount)

    def settle(self) -> None:
        """The round ends: the writes and the scent take effect."""
        self.value, self.colour = self.read()
        self.pheromone += self.pending[2]
        self.pending = (None, None, 0.0)


@dataclass
class FakeGridGripper:
    """Picking and dropping (``robots.grid_hal.GridGripper``): ``lying`` units lie under the
    robot; a pick and a drop happen at the round's end (:meth:`settle`), the pick first;
    ``dropped`` counts the units dropped."""

    load: int = 0
    lying: int = 0
    dropped: int = 0
    picking: int = 0  # units asked for this round
    dropping: bool = False  # whether a drop was asked for this round

    def carried(self) -> int:
        """Units carried now."""
        return self.load

    def pick(self, units: int) -> None:
        """Pick up to ``units`` at this round's end."""
        self.picking = units

    def drop(self) -> None:
        """Drop the load at this round's end."""
        self.dropping = True

    def settle(self) -> None:
        """The round ends: pick what lies here (as much as asked), then drop."""
        taken = min(self.picking, self.lying)
        self.lying -= taken
        self.load += taken
        if self.dropping:
            self.dropped += self.load
            self.load = 0
        self.picking, self.dropping = 0, False


@dataclass
class FakeGridRadio:
    """The radio (``robots.grid_hal.GridRadio``): its ``range`` in cells, the ``located``
    position the transport reads, and the members it ``hears`` this round, as the test sets."""

    range: float = math.inf
    located: tuple[float, float, float] | None = None
    hears: frozenset[str] = frozenset()

    def position(self) -> tuple[float, float, float] | None:
        """The centre of the robot's cell (transport only)."""
        return self.located

    def in_range(self) -> frozenset[str]:
        """Members within radio range this round."""
        return self.hears


def fake_grid_hardware(
    id: str = "robot",
    *,
    clock: FakeRoundClock | None = None,
    drive: FakeGridDrive | None = None,
    odometry: FakeGridOdometry | None = None,
    senses: FakeGridSenses | None = None,
    floor: FakeGridFloor | None = None,
    gripper: FakeGridGripper | None = None,
    radio: FakeGridRadio | None = None,
) -> GridHardware:
    """A :class:`robots.grid_hal.GridHardware` of fakes (new ones where none is given; no radio
    unless given): each round's end moves the odometry as the drive went and settles the floor
    and the gripper; an idle block stops the drive. Pass the fakes a test wants to steer or
    read."""
    clock = clock or FakeRoundClock()
    drive = drive or FakeGridDrive()
    odometry = odometry or FakeGridOdometry()
    floor = floor or FakeGridFloor()
    gripper = gripper or FakeGridGripper()

    def round_end() -> None:
        odometry.follow(drive.settle())
        floor.settle()
        gripper.settle()

    clock.on_tick.append(round_end)
    clock.on_idle.append(drive.stop)
    return GridHardware(
        id=id,
        clock=clock,
        drive=drive,
        odometry=odometry,
        senses=senses or FakeGridSenses(),
        floor=floor,
        gripper=gripper,
        radio=radio,
    )
