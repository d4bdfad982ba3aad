"""The ``grid`` hardware backend: a robot's grid HAL (robots/grid_hal.py) over a grid world.

:class:`GridRobot` collects this round's action and keeps the last perception in a
:class:`sim_hw._ticks.Ticks` (the robot's clock over its link to the world: one exchange per
round, a cancelled one finished in the background, idling).

Rounds belong to whoever drives them. A program that owns the clock (:meth:`GridRobot.owned`)
has its rounds to itself: nothing is sent for a round until it has decided; until the round it
starts at, the clock hands in empty actions itself. Other tasks' ticks are paced
(``idle_period``) and stop while the clock is owned. A robot that runs nothing is idle
(:meth:`GridRobot.idling`): the world does not wait for it.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
from collections.abc import AsyncIterator, Mapping
from typing import TYPE_CHECKING, Any

from robots.grid_hal import OFFSETS, GridHardware, Here, Near, Seen
from robots.hal import Changes
from sim_hw import _link
from sim_hw._link import WorldLink
from sim_hw._robot import ClockView, TickedRobot
from sim_hw._ticks import Ticks

if TYPE_CHECKING:
    from mover import Node

    from ._server import GridServer

_OWNER: contextvars.ContextVar[object | None] = contextvars.ContextVar("grid_owner", default=None)


class GridRobot(TickedRobot):
    """Perception cache, action buffer and round clock of one grid robot."""

    def __init__(
        self,
        robot_id: str,
        spec: dict[str, Any],
        readings: dict[str, Any],
        link: WorldLink,
        *,
        idle_period: float = 0.01,
    ) -> None:
        self.id = robot_id
        self.spec = spec
        self.idle_period = idle_period
        self.range = float(spec.get("radio", float("inf")))
        self._ticks = Ticks(
            robot_id,
            link,
            readings,
            tick_of=lambda r: int(r["round"]),
            time_of=lambda r: float(r["round"]),
            period=1.0,
            after=self._moved,
        )
        self._action: dict[str, Any] = {}
        self._offset = [0, 0]
        self._lock = asyncio.Lock()
        self._owner: object | None = None
        self._hold_at: int | None = None
        self._changed = Changes()

    @property
    def readings(self) -> dict[str, Any]:
        """The current perception."""
        readings: dict[str, Any] = self._ticks.readings
        return readings

    # -- the clock ------------------------------------------------------------------------------

    def now(self) -> int:
        """The round of the current perception."""
        return int(self.readings["round"])

    def ended(self) -> bool:
        """Whether the world's observer ended the run."""
        return bool(self.readings.get("over", False))

    def _held(self) -> bool:
        if self._owner is not None and _OWNER.get() is not self._owner:
            return True
        return self._owner is None and self._hold_at is not None and self.now() >= self._hold_at

    async def tick(self) -> None:
        """Send this round's action and wait for the next perception.

        The owner of the clock exchanges at once; any other task waits while the clock is
        owned or held, and is paced by ``idle_period``.
        """
        owner = self._owner is not None and _OWNER.get() is self._owner
        while True:
            if not owner:
                while self._held():
                    await self._wait_change()
                await asyncio.sleep(self.idle_period)
            async with self._lock:
                if not owner and self._held():
                    continue
                await self._ticks.tick(self._take_action)
            self._notify()
            return

    def _take_action(self) -> dict[str, Any]:
        action, self._action = self._action, {}
        return action

    def _moved(self, action: Mapping[str, Any], readings: Mapping[str, Any]) -> None:
        """An exchange ended (in its own task, even if its caller was cancelled)."""
        wanted = action.get("move")
        if wanted is not None and readings.get("moved"):
            dr, dc = OFFSETS[int(wanted)]
            self._offset[0] += dr
            self._offset[1] += dc

    def _notify(self) -> None:
        self._changed.pulse()

    async def _wait_change(self) -> None:
        await self._changed.wait()

    def _idle(self) -> dict[str, Any]:
        """The robot stays: the action an idle robot stands on."""
        self._action.pop("move", None)
        return {}

    @contextlib.asynccontextmanager
    async def owned(self, at: int) -> AsyncIterator[None]:
        """Drive the rounds from round ``at`` (see robots.grid_hal.RoundClock.owned)."""
        if self._owner is not None or self._hold_at is not None:
            raise RuntimeError("the clock is already owned")
        self._hold_at = at
        self._notify()
        try:
            while self.now() < at:  # no one else need tick us there: stay until round ``at``
                async with self._lock:  # after any exchange under way
                    if self.now() < at:
                        await self._ticks.tick(dict)
                self._notify()
            if self.now() != at:
                raise RuntimeError(f"round {at} had already passed (now {self.now()})")
            token = object()
            self._owner = token
            reset = _OWNER.set(token)
            try:
                yield
            finally:
                _OWNER.reset(reset)
        finally:
            self._owner = None
            self._hold_at = None
            self._notify()

    # -- senses -----------------------------------------------------------------------------------

    def here(self) -> Here:
        """The cell under the robot."""
        v, col, res, base, ph = self.readings["here"]
        return Here(int(v), int(col), int(res), bool(base), float(ph))

    def around(self) -> tuple[Near, ...]:
        """The neighbouring cells, in direction order."""
        return tuple(
            Near(int(d), int(s), int(v), int(c), int(r), bool(b), float(p))
            for d, s, v, c, r, b, p in self.readings["around"]
        )

    def rays(self) -> tuple[Seen, ...]:
        """Cells seen along the view rays, relative to the robot."""
        return tuple(Seen(int(dr), int(dc), bool(v)) for dr, dc, v in self.readings["rays"])

    def compass(self) -> tuple[float, float]:
        """Unit vector toward the base."""
        hr, hc = self.readings["home"]
        return (float(hr), float(hc))

    # -- actions ----------------------------------------------------------------------------------

    def read(self) -> tuple[int, int]:
        """(value, colour) under the robot; a pending write shows at once."""
        v, c = self.readings["here"][:2]
        return (int(self._action.get("value", v)), int(self._action.get("colour", c)))

    def write(self, value: int | None = None, colour: int | None = None) -> None:
        """Write the cell under the robot at this round's end."""
        if value is not None:
            self._action["value"] = int(value)
        if colour is not None:
            self._action["colour"] = int(colour)

    def scent(self, amount: float) -> None:
        """Add pheromone here at this round's end."""
        if amount:
            self._action["drop"] = float(self._action.get("drop", 0.0)) + float(amount)

    def carried(self) -> int:
        """Units carried (as of the last perception)."""
        return int(self.readings["carried"])

    def pick(self, units: int) -> None:
        """Pick up to ``units`` here at this round's end."""
        if units:
            self._action["load"] = int(units)

    def drop(self) -> None:
        """Drop the load at this round's end."""
        self._action["unload"] = True

    def move(self, direction: int | None) -> None:
        """Move one cell at this round's end (None: stay)."""
        if direction is None:
            self._action.pop("move", None)
        else:
            self._action["move"] = int(direction)

    def stop(self) -> None:
        """Stay this round."""
        self._action.pop("move", None)

    def moved(self) -> bool:
        """Whether the last round's move happened."""
        return bool(self.readings.get("moved", False))

    def pose(self) -> tuple[float, float, float]:
        """Cells moved since the start: (d_row, d_col, 0)."""
        return (float(self._offset[0]), float(self._offset[1]), 0.0)

    def position(self) -> tuple[float, float, float] | None:
        """The radio's locator: the centre of the robot's cell (transport only)."""
        loc = self.readings.get("loc")
        return None if loc is None else (float(loc[0]), float(loc[1]), float(loc[2]))

    def in_range(self) -> frozenset[str]:
        """Members within radio range this round, as the medium says."""
        return frozenset(self.readings.get("hears", ()))

    def hardware(self) -> GridHardware:
        """The HAL bundle for robot code."""
        return GridHardware(
            id=self.id,
            clock=_Clock(self),
            drive=_Drive(self),
            odometry=_Odometry(self),
            senses=_Senses(self),
            floor=_Floor(self),
            gripper=_Gripper(self),
            radio=_Radio(self),
        )


# Thin device views, so that each HAL protocol exposes only its own methods.


class _Clock(ClockView):
    def __init__(self, robot: GridRobot) -> None:
        super().__init__(robot)
        self.now, self.ended = robot.now, robot.ended
        self.tick, self.owned = robot.tick, robot.owned


class _Drive:
    def __init__(self, robot: GridRobot) -> None:
        self.move, self.stop, self.moved = robot.move, robot.stop, robot.moved


class _Odometry:
    def __init__(self, robot: GridRobot) -> None:
        self.pose = robot.pose


class _Senses:
    def __init__(self, robot: GridRobot) -> None:
        self.here, self.around = robot.here, robot.around
        self.rays, self.compass = robot.rays, robot.compass


class _Floor:
    def __init__(self, robot: GridRobot) -> None:
        self.read, self.write, self.scent = robot.read, robot.write, robot.scent


class _Gripper:
    def __init__(self, robot: GridRobot) -> None:
        self.carried, self.pick, self.drop = robot.carried, robot.pick, robot.drop


class _Radio:
    def __init__(self, robot: GridRobot) -> None:
        self.range = robot.range
        self.position, self.in_range = robot.position, robot.in_range


async def in_process(
    server: GridServer,
    robot_id: str,
    spec: Mapping[str, Any] | None = None,
    *,
    idle_period: float = 0.0,
) -> GridHardware:
    """Join ``server`` (a :class:`~sim_hw.grid.GridServer` in this process)."""
    joined, link = await _link.in_process(server.door, robot_id, spec)
    return GridRobot(
        robot_id, joined["spec"], joined["readings"], link, idle_period=idle_period
    ).hardware()


async def connect(
    node: Node,
    robot_id: str,
    spec: Mapping[str, Any] | None = None,
    *,
    world: str = "gridworld",
    call_timeout: float = 30.0,
    idle_period: float = 0.01,
) -> GridHardware:
    """Join the grid world process ``world`` over ``node`` (a ``mover.Node``); return the HAL.

    One exchange per round (a frame each way where the world offers it, else a call; see
    ``sim_hw._link``); a call not answered in ``call_timeout`` s is asked again while the
    world is alive. The robot's id must be its node's name: the world drops the robot when
    that member leaves the team.
    """
    joined, link = await _link.remote(node, robot_id, spec, world=world, call_timeout=call_timeout)
    return GridRobot(
        robot_id, joined["spec"], joined["readings"], link, idle_period=idle_period
    ).hardware()
