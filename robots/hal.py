"""The hardware-abstraction layer: what a robot process needs from its hardware.

The robot side owns these interfaces (``typing.Protocol``s); the simulated hardware in
``sim_hw`` (in-process or over zenoh) and, one day, real robots satisfy them structurally.
Nothing here imports pymunk or ``sim_hw``.

Conventions:

* Units are SI: metres, seconds, radians, newtons. Angles are counter-clockwise; a bearing is
  measured from the robot's heading (positive to the left), in (-π, π].
* Sensors are read without waiting: a reading is the value measured at the last control tick.
  Actuator commands (drive, LED, floor writes) take effect at the next tick.
* Time is the hardware's own clock (simulated time in simulation): a robot waits with
  ``await hw.clock.tick()`` or ``await hw.clock.sleep(dt)``, never with ``asyncio.sleep``.
* The robot never gets ground truth, except through the radio locator, which exists only so
  that the transport's range-limited broadcast can compute ranges.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable
from contextlib import AbstractAsyncContextManager
from dataclasses import dataclass
from typing import Literal, Protocol, TypeVar, runtime_checkable

from mover import ExpectedFault, IdleClock

__all__ = [
    "MARK",
    "MARKED",
    "Bumper",
    "BumperSide",
    "Camera",
    "Changes",
    "Clock",
    "Drive",
    "FloorCell",
    "FloorCells",
    "Hardware",
    "HardwareLost",
    "Led",
    "LostLatch",
    "NoWorldAhead",
    "Odometry",
    "PushResult",
    "PushSense",
    "RadioLocator",
    "Sighting",
    "Sonar",
    "sleep_in_ticks",
]

T = TypeVar("T")

Pose = tuple[float, float, float]
"""(x, y, heading) in metres and radians."""

BumperSide = Literal["front", "left", "right", "back"]
"""Which part of the bumper ring is pressed (front is ±45° around the heading)."""


@dataclass(frozen=True, slots=True)
class Sighting:
    """One thing the camera sees.

    ``kind`` is e.g. ``"robot"``, ``"box"``, ``"immovable"``, ``"target"``, ``"beacon"``,
    ``"resource"``; ``status`` is what it shows (a robot's LED, a beacon's code, a resource's
    amount as text). ``range`` is centre to centre in metres; ``bearing`` is relative to the
    robot's heading, in radians.
    """

    kind: str
    id: str
    status: str
    range: float
    bearing: float


@dataclass(frozen=True, slots=True)
class FloorCell:
    """The content of one floor cell: an integer and a colour name (``""`` when unset)."""

    value: int
    colour: str


#: How a robot talks to a passive target (its LED) and how a marked one looks (its status).
MARK = "mark:"
"""LED prefix of a robot's message to a target: ``mark:<id>`` marks target ``<id>``."""
MARKED = "marked"
"""The status a marked target shows to cameras (its "repelling signal")."""


class HardwareLost(ExpectedFault):
    """The hardware went away: a simulated world that stopped, a body that dropped the robot.

    Raised by a device call or a clock tick; the robot process waits for the hardware and
    connects again, and a program that was running fails with it (an expected fault: reported
    in one line, not as a bug).
    """


class NoWorldAhead:
    """The ``reach`` of a clock that no world runs ahead of (a real robot's, a fake's): a robot
    is sure to get past ``t`` at ``t`` itself (see :meth:`mover.IdleClock.reach`)."""

    def reach(self, t: float) -> float:
        """``t``: no world runs ahead of this robot's commands."""
        return t


class Changes:
    """Something that changes now and then, and the tasks that wait for its next change:
    :meth:`wait` returns at the next :meth:`pulse`. The event is made only while someone
    waits (a clock pulses every tick, mostly with no one waiting)."""

    __slots__ = ("_event",)

    def __init__(self) -> None:
        self._event: asyncio.Event | None = None

    def pulse(self) -> None:
        """Wake every task in :meth:`wait`."""
        if self._event is not None:
            self._event.set()
            self._event = None

    async def wait(self) -> None:
        """Return at the next :meth:`pulse`."""
        if self._event is None:
            self._event = asyncio.Event()
        await self._event.wait()


class LostLatch:
    """The part of a ticking clock that keeps the hardware's loss and wakes its waits (a base
    of the Thymio's clock and of the simulated robot's ticks).

    :meth:`lose` keeps the first :class:`HardwareLost` and wakes every wait; from then on
    :meth:`_check` raises it. :meth:`_guard` awaits a call of the hardware's and loses on its
    HardwareLost (raised again). :meth:`_pulse` wakes every :meth:`_wait_change`.
    """

    def __init__(self) -> None:
        self._lost: HardwareLost | None = None
        self._changes = Changes()

    def lose(self, exc: HardwareLost) -> None:
        """The hardware went away: every wait raises ``exc`` from now on."""
        if self._lost is None:
            self._lost = exc
        self._pulse()

    async def _guard(self, call: Awaitable[T]) -> T:
        try:
            return await call
        except HardwareLost as exc:
            self.lose(exc)
            raise

    def _check(self) -> None:
        if self._lost is not None:
            raise self._lost

    def _pulse(self) -> None:
        self._changes.pulse()

    async def _wait_change(self) -> None:
        await self._changes.wait()


@dataclass(frozen=True, slots=True)
class PushResult:
    """Outcome of a push test: what was pushed, how far it moved, and whether that counts.

    ``object_id`` is ``None`` when nothing was in front of the robot.
    """

    object_id: str | None
    displacement: float
    moved: bool


@runtime_checkable
class Drive(Protocol):
    """Differential drive, commanded by forward speed and turn rate."""

    max_speed: float
    """Largest forward speed in m/s; faster commands are clipped."""

    def set_velocity(self, v: float, omega: float) -> None:
        """Drive at ``v`` m/s forward and ``omega`` rad/s (counter-clockwise) from the next tick."""
        ...

    def stop(self) -> None:
        """Stop both wheels from the next tick."""
        ...


@runtime_checkable
class Sonar(Protocol):
    """A ring of range sensors."""

    angles: tuple[float, ...]
    """Direction of each ray relative to the heading, in radians."""
    max_range: float
    """A ray that hits nothing reads this value (metres)."""

    def ranges(self) -> tuple[float, ...]:
        """Distance from the robot's rim to the nearest obstacle along each ray (noisy)."""
        ...


@runtime_checkable
class Bumper(Protocol):
    """A contact ring around the robot."""

    def pressed(self) -> bool:
        """Whether anything touches the robot."""
        ...

    def side(self) -> BumperSide | None:
        """Which part of the ring is pressed, or ``None``."""
        ...


@runtime_checkable
class Odometry(Protocol):
    """Dead reckoning from wheel motion: drifts with the configured noise."""

    def pose(self) -> Pose:
        """The dead-reckoned (x, y, heading); starts at the robot's spawn pose."""
        ...


@runtime_checkable
class Camera(Protocol):
    """Detects robots and objects within a range and field of view."""

    max_range: float
    fov: float
    """Full field of view in radians, centred on the heading."""

    def sightings(self) -> tuple[Sighting, ...]:
        """What is visible now, nearest first."""
        ...


@runtime_checkable
class Led(Protocol):
    """A status light other robots' cameras can read."""

    def show(self, status: str) -> None:
        """Show ``status`` from the next tick."""
        ...


@runtime_checkable
class RadioLocator(Protocol):
    """Where the radio is, for the transport's range-limited broadcast only.

    Behaviours must not use this: it is ground truth.
    """

    def position(self) -> Pose | None:
        """Ground-truth (x, y, heading), or ``None`` when unknown."""
        ...


@runtime_checkable
class FloorCells(Protocol):
    """A floor of writable cells (an RFID floor): one integer and one colour per cell."""

    def read(self) -> FloorCell:
        """The cell under the robot's centre."""
        ...

    def write(self, value: int, colour: str = "") -> None:
        """Write the cell under the robot (applied at the next tick; read() shows it at once)."""
        ...


@runtime_checkable
class PushSense(Protocol):
    """MOVER's "movable?" test: push what is in front with a bounded force and watch it."""

    async def push(self, force: float, duration: float) -> PushResult:
        """Drive forward for ``duration`` s with at most ``force`` N; stop; report the motion."""
        ...


@runtime_checkable
class Clock(IdleClock, Protocol):
    """The hardware's clock: simulated time in simulation, in seconds.

    ``now``, ``passed``, ``hold`` and ``idling`` are :class:`mover.IdleClock`'s. While idle the
    readings stay current where the world sends them; ``tick()`` raises RuntimeError, and
    ``await passed(math.inf)`` waits until the hardware is lost (HardwareLost). A real-time
    world ticks on its own.
    """

    tick_period: float
    """Seconds of hardware time between control ticks."""

    async def tick(self) -> None:
        """Send this tick's commands and wait for the next tick's readings.

        The readings change only inside this robot's own clock calls: if an earlier ``tick()``
        was cancelled once its commands went in (a ``distributed_or``'s loser), the readings
        stay as they were until the next ``tick()``, which takes that tick's readings and hands
        in nothing more (the commands set meanwhile go with the tick after)."""
        ...

    async def sleep(self, dt: float) -> None:
        """Let ``dt`` seconds of hardware time pass (whole ticks, at least one)."""
        ...

    def ticking(self) -> AbstractAsyncContextManager[None]:
        """Keep the hardware ticking, with the current commands, while the block awaits
        something else (a message, a team step).

        In lock-step simulation the world waits for the command of every robot that is not
        idle each tick; a robot waiting on something outside the world (a message, a person)
        must keep ticking. Team steps need no ``ticking()``: in simulated time they idle the
        clock while a member waits for the others, and the background ticks pause meanwhile.
        On hardware with its own clock this does nothing.
        """
        ...


async def sleep_in_ticks(clock: Clock, dt: float) -> None:
    """:meth:`Clock.sleep` for a clock whose time moves by ticks: tick until ``dt`` seconds of
    hardware time have passed, at least one tick."""
    end = clock.now() + dt - 1e-9
    await clock.tick()
    while clock.now() < end:
        await clock.tick()


@dataclass(frozen=True, slots=True)
class Hardware:
    """Everything a robot process can touch, grouped; a device is ``None`` when absent."""

    id: str
    clock: Clock
    drive: Drive
    odometry: Odometry
    sonar: Sonar | None = None
    bumper: Bumper | None = None
    camera: Camera | None = None
    led: Led | None = None
    radio: RadioLocator | None = None
    floor: FloorCells | None = None
    push: PushSense | None = None
