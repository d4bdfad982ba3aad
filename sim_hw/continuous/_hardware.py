"""The robots' hardware interface (robots/hal.py) implemented on a simulated world.

One class, :class:`SimHardware`, serves both backends: it collects the commands for the next
tick and keeps the readings of the last one in a :class:`sim_hw._ticks.Ticks`, the robot's
clock over a link to its world — a direct call into a :class:`WorldServer` in process, or one
exchange of frames per tick with the world process. Concurrent waiters on a tick share one
exchange, so a robot sends exactly one command per tick however many of its tasks wait, and a
cancelled tick finishes in the background (the world never sees half of one), its readings
taken by the next tick.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections.abc import AsyncIterator, Coroutine, Mapping
from typing import TYPE_CHECKING, Any

from robots.hal import (
    BumperSide,
    FloorCell,
    Hardware,
    PushResult,
    Sighting,
    sleep_in_ticks,
)
from sim_hw import _link
from sim_hw._link import WorldLink
from sim_hw._robot import ClockView, TickedRobot
from sim_hw._ticks import Ticks

from ._contract import TICK, Command, Readings

if TYPE_CHECKING:
    from mover import Node

    from ._stepper import WorldServer

log = logging.getLogger("sim_hw.hardware")

PUSH_SPEED = 0.2
"""Forward speed (m/s) a push test asks for; the force bound decides whether it is reached."""
MOVED = 0.02
"""Displacement (m) above which a pushed object counts as moved."""


class SimHardware(TickedRobot):
    """Command buffer and clock of one simulated robot; its devices are views of it."""

    tick_period = TICK

    def __init__(
        self, robot_id: str, spec: dict[str, Any], readings: Readings, link: WorldLink
    ) -> None:
        self.id = robot_id
        self.spec = spec
        self._ticks = Ticks(
            robot_id,
            link,
            readings,
            tick_of=lambda r: int(r["tick"]),
            time_of=lambda r: float(r["t"]),
            period=TICK,
        )
        self._v = 0.0
        self._w = 0.0
        self._push: float | None = None
        self._led: str | None = None
        self._floor: list[Any] | None = None
        self._pump: asyncio.Task[None] | None = None
        self._pumps = 0
        self._paused_said = False  # the pump paused for idling, said once
        self.max_speed = float(spec.get("max_speed", 0.0))  # an eye-bot has no drive

    @property
    def readings(self) -> Readings:
        """The readings of the last tick."""
        readings: Readings = self._ticks.readings
        return readings

    # -- clock ---------------------------------------------------------------------------------

    def now(self) -> float:
        """Simulated time of the last readings."""
        return self._ticks.now()

    def tick(self) -> Coroutine[Any, Any, None]:
        """Send this tick's command, wait for the next readings (shared by concurrent callers).

        (The clock's coroutine itself, not one awaiting it: a frame less a robot a tick.)"""
        return self._ticks.tick(self._command)

    def _command(self) -> Command:
        command: Command = {"v": self._v, "w": self._w, "push": self._push}
        if self._led is not None:
            command["led"] = self._led
        if self._floor is not None:
            command["floor"] = self._floor
        self._floor = None
        return command

    def _idle(self) -> Command:
        """Stop the drive: the command an idle robot stands on."""
        self.stop()
        self._push = None
        return {"v": 0.0, "w": 0.0, "push": None}

    async def sleep(self, dt: float) -> None:
        """Tick until ``dt`` simulated seconds have passed (at least one tick)."""
        await sleep_in_ticks(self, dt)

    @contextlib.asynccontextmanager
    async def ticking(self) -> AsyncIterator[None]:
        """Tick in the background for the duration of the block (nested blocks are fine).

        While the robot is idle or held (a team step in simulated time idles a member as it
        waits for the others, and holds it from where its operation ended until the step is
        over) the background ticks pause: the earlier advice to keep the clock ticking around
        team steps still runs, and runs alike every time, though steps no longer need it
        (said once in the log). On the way out the exchange under way is finished, not
        cancelled, so the world never sees half a tick.
        """
        self._pumps += 1
        pump = self._pump
        if pump is None or pump.done():
            pump = self._pump = asyncio.get_running_loop().create_task(self._run_pump())
        try:
            yield
        finally:
            self._pumps -= 1
            if self._pumps == 0:
                self._ticks.poke()  # a paused pump sees that the block ended
                await asyncio.shield(pump)

    async def _run_pump(self) -> None:
        while self._pumps > 0:
            ticks = self._ticks
            if not (ticks.idle or ticks.held):  # (no await between this and the tick)
                await ticks.tick(self._command)
                await asyncio.sleep(0)  # let the block's own tasks run between ticks
                continue
            if ticks.idle and not self._paused_said:
                self._paused_said = True
                log.warning(
                    "robot %s: clock.ticking() pauses while a team step idles the robot; "
                    "team steps need no ticking() around them any more",
                    self.id,
                )
            await ticks.changed()  # paused while a team step idles or holds the robot

    # -- drive, LED, floor ----------------------------------------------------------------------

    def set_velocity(self, v: float, omega: float) -> None:
        """Drive command for the next tick (clipped by the world to the robot's limits)."""
        self._v, self._w = float(v), float(omega)

    def stop(self) -> None:
        """Zero both speeds from the next tick."""
        self._v = self._w = 0.0

    def show(self, status: str) -> None:
        """Set the LED status others' cameras read."""
        self._led = str(status)

    def read(self) -> FloorCell:
        """The floor cell under the robot (a pending write shows at once)."""
        value, colour = self._floor if self._floor is not None else self.readings["floor"]
        return FloorCell(int(value), str(colour))

    def write(self, value: int, colour: str = "") -> None:
        """Write the floor cell under the robot at the next tick."""
        self._floor = [int(value), str(colour)]

    # -- sensors --------------------------------------------------------------------------------

    def ranges(self) -> tuple[float, ...]:
        """Sonar ranges of the last tick."""
        return tuple(self.readings["sonar"] or ())

    def pressed(self) -> bool:
        """Whether the bumper touches anything."""
        return self.readings["bump"] is not None

    def side(self) -> BumperSide | None:
        """Which side of the bumper touches."""
        side: BumperSide | None = self.readings["bump"]
        return side

    def pose(self) -> tuple[float, float, float]:
        """Dead-reckoned pose."""
        x, y, th = self.readings["odom"]
        return (float(x), float(y), float(th))

    def sightings(self) -> tuple[Sighting, ...]:
        """Camera detections of the last tick."""
        return tuple(
            Sighting(str(k), str(i), str(s), float(r), float(b))
            for k, i, s, r, b in self.readings["cam"] or ()
        )

    def position(self) -> tuple[float, float, float] | None:
        """Ground-truth pose from the radio locator (for the transport only)."""
        loc = self.readings["loc"]
        return None if loc is None else (float(loc[0]), float(loc[1]), float(loc[2]))

    async def push(self, force: float, duration: float) -> PushResult:
        """Push forward with at most ``force`` N for ``duration`` s, stop, report the motion."""
        self._push = float(force)
        self._v, self._w = PUSH_SPEED, 0.0
        try:
            await self.sleep(duration)
            got = self.readings["push"]
        finally:
            self._push = None
            self.stop()
        if got is None:
            return PushResult(None, 0.0, False)
        obj, disp = got
        return PushResult(obj, float(disp), float(disp) >= MOVED)

    def hardware(self) -> Hardware:
        """The HAL bundle for robot code."""
        spec = self.spec
        sonar = spec.get("sonar")
        camera = spec.get("camera")
        return Hardware(
            id=self.id,
            clock=_Clock(self),
            drive=_Drive(self),
            odometry=_Odometry(self),
            sonar=_Sonar(self, sonar) if sonar else None,
            bumper=_Bumper(self),
            camera=_Camera(self, camera) if camera else None,
            led=_Led(self),
            radio=_Radio(self) if spec.get("radio", True) else None,
            floor=_Floor(self),
            push=_Push(self),
        )


# Thin device views, so that each HAL protocol exposes only its own methods.


class _Clock(ClockView):
    tick_period = TICK

    def __init__(self, hw: SimHardware) -> None:
        super().__init__(hw)
        self.now, self.tick, self.sleep, self.ticking = hw.now, hw.tick, hw.sleep, hw.ticking


class _Drive:
    def __init__(self, hw: SimHardware) -> None:
        self.max_speed = hw.max_speed
        self.set_velocity, self.stop = hw.set_velocity, hw.stop


class _Odometry:
    def __init__(self, hw: SimHardware) -> None:
        self.pose = hw.pose


class _Sonar:
    def __init__(self, hw: SimHardware, spec: dict[str, Any]) -> None:
        n = int(spec["rays"])
        self.angles = tuple(2.0 * math.pi * i / n for i in range(n))
        self.max_range = float(spec["max_range"])
        self.ranges = hw.ranges


class _Bumper:
    def __init__(self, hw: SimHardware) -> None:
        self.pressed, self.side = hw.pressed, hw.side


class _Camera:
    def __init__(self, hw: SimHardware, spec: dict[str, Any]) -> None:
        self.max_range = float(spec["max_range"])
        self.fov = float(spec["fov"])
        self.sightings = hw.sightings


class _Led:
    def __init__(self, hw: SimHardware) -> None:
        self.show = hw.show


class _Radio:
    def __init__(self, hw: SimHardware) -> None:
        self.position = hw.position


class _Floor:
    def __init__(self, hw: SimHardware) -> None:
        self.read, self.write = hw.read, hw.write


class _Push:
    def __init__(self, hw: SimHardware) -> None:
        self.push = hw.push


async def in_process(
    server: WorldServer, robot_id: str, spec: Mapping[str, Any] | None = None
) -> Hardware:
    """Join ``server`` (a :class:`WorldServer` in this process) and return the robot's HAL."""
    joined, link = await _link.in_process(server.door, robot_id, spec)
    return SimHardware(robot_id, joined["spec"], joined["readings"], link).hardware()


async def remote(
    node: Node,
    robot_id: str,
    spec: Mapping[str, Any] | None = None,
    *,
    world: str = "world",
    call_timeout: float = 30.0,
) -> Hardware:
    """Join the world process ``world`` over ``node`` (a ``mover.Node``); return the HAL.

    One exchange per tick (a frame each way where the world offers it, else a call; see
    ``sim_hw._link``); a call not answered in ``call_timeout`` s is asked again while the
    world is alive. The robot's id must be its node's name.
    """
    joined, link = await _link.remote(node, robot_id, spec, world=world, call_timeout=call_timeout)
    return SimHardware(robot_id, joined["spec"], joined["readings"], link).hardware()
