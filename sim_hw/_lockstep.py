"""The lock-step door of both worlds: robots join, hand in one command per tick, get readings.

Written once, against the :class:`Stepper` protocol (``sim_hw._types``): the pymunk world and
the grid world are adapters to it. A **schedule** (``sim_hw._schedules``) owns the commands
handed in and decides when a tick runs; the door owns the rest:

* **joins** — the stepper checks a join's settings at once (a bad spec fails the join) and
  the robot is placed at the next tick boundary (at once if no robot is waited for), robots
  that wait together in id order. Before the first tick the door waits for ``expect``
  robots: a stepper that ``admits_early`` (pymunk) has each in the world at once and
  re-creates them all in id order at the start (:meth:`Stepper.start`); the others (the grid)
  hold the joins and place them all then, in id order. Every join is answered at the start,
  with the readings after it, whatever order the joins came in. A repeated join (a retry)
  gets the same, shielded answer.
* **idle robots** — :meth:`LockstepDoor.idle` gives a robot a standing command (its stopped
  drive), applied at every tick; the door does not wait for it until :meth:`LockstepDoor.wake`
  or its next command. Idle robots stay in the world and keep getting readings. A world whose
  robots are all idle holds still (no tick, no timer) and places a join at once. ``expect``
  counts idle robots as in.
* **silence and drops** — ``timeout`` wall seconds after a tick's first command, each robot
  still missing is named once (``waiting for robot X: tick N, K s``); with ``drop_silent``
  (worlds in one process) it is then dropped and the tick goes on. A world process turns
  ``drop_silent`` off (``sim_hw._process``): liveness decides, through :meth:`LockstepDoor.drop`.
* **answers** — after a tick: the callers' waiters (shielded: a caller that gives up does not
  take a retry's answer down), the watchers of idle robots, then the ``on_tick`` hooks (the
  one way a world, a recorder or the frames hear of a tick). :meth:`LockstepDoor.keep` owns
  every task.

The schedules. **Lock-step** (default): a tick runs once every robot that is not idle has
handed in its command; commands are applied in id order; the first command for a tick is the
one used, a later one or one for a tick already done is a retry (answered with the readings
after that tick, never applied). **Real time** (``speed``): a tick every ``period / speed``
wall seconds whoever has answered (a late robot keeps its last command). **Sequential turns**
(``turns="sequential"``): a round in which robots that are not idle act one at a time in id
order, each perceiving just before its own turn (Simonin et al., section 5.1). **Lock-step with
a control delay** (``control_delay=K``): a command handed in for tick t applies at tick t + K,
so that the world runs up to K ticks ahead of its robots (``sim_hw._delayed``).

Same seeds, world and commands: the same run, however long (in wall time) the world held
still in between. Cost: one dict entry per robot per tick, a future per calling robot.
"""

from __future__ import annotations

import asyncio
import gc
import logging
from collections.abc import Callable, Mapping
from typing import Any, Generic, TypeVar

from mover._futures import running_loop

from ._delayed import Delayed
from ._schedules import Lockstep, RealTime, Schedule, Turns
from ._types import Command, Readings, RobotDropped, Stepper, TurnStepper

__all__ = [
    "Command",
    "LockstepDoor",
    "Readings",
    "RobotDropped",
    "Stepper",
    "TickHook",
    "TurnStepper",
]

log = logging.getLogger("sim_hw.lockstep")

S = TypeVar("S", bound=Stepper)

TickHook = Callable[[Mapping[str, Command]], None]
"""Called after every tick with the commands applied (empty for a round of turns)."""

_Join = tuple[str, "asyncio.Future[dict[str, Any]]"]


class LockstepDoor(Generic[S]):
    """Runs a :class:`Stepper` by a schedule (see the module) for the robots that join it.

    ``expect`` robots must join before the first tick (0: start at the first join).
    ``timeout`` wall seconds after a tick's first command, a missing robot is logged, and
    dropped if ``drop_silent``. The schedule is lock-step, or real time with ``speed`` (a tick
    of ``period`` simulated seconds), or ``turns="sequential"``, or lock-step with a
    ``control_delay`` of K ticks; or one given as ``schedule``.
    ``on_tick`` hooks (:data:`TickHook`) are called after every tick with the commands applied.
    """

    def __init__(
        self,
        stepper: S,
        *,
        expect: int = 0,
        timeout: float = 2.0,
        drop_silent: bool = True,
        speed: float | None = None,
        period: float = 0.1,
        turns: str = "together",
        schedule: Schedule | None = None,
        control_delay: int = 0,
    ) -> None:
        self.stepper = stepper
        self.control_delay = control_delay
        self.expect = expect
        self.timeout = timeout
        self.drop_silent = drop_silent
        self.schedule = schedule or _schedule(stepper, speed, period, turns, control_delay)
        self.dropped: list[str] = []
        self.on_tick: list[TickHook] = []
        self.started = expect <= 0
        self.joins: dict[str, tuple[Any, asyncio.Future[dict[str, Any]]]] = {}
        # admitted early (before the start): answered at the start, with the readings then
        self._early: dict[str, asyncio.Future[dict[str, Any]]] = {}
        self.idles: dict[str, dict[str, Any]] = {}  # idle robot -> its standing command
        self._waiters: dict[str, asyncio.Future[Readings]] = {}
        self._watchers: dict[str, list[Callable[[Readings | None], None]]] = {}
        self.reported: set[str] = set()  # robots said to be waited for in this tick
        self._deadline: asyncio.TimerHandle | None = None
        self._background: set[asyncio.Task[Any]] = set()
        self._finish: set[asyncio.Task[Any]] = set()  # of those, the ones let to end
        self.closed = False
        self.schedule.bind(self)

    @property
    def lockstep(self) -> bool:
        """Whether the world waits for every robot (not real time)."""
        return self.schedule.lockstep

    @property
    def turns(self) -> str:
        """``together`` or ``sequential``."""
        return self.schedule.turns

    @property
    def idle_robots(self) -> frozenset[str]:
        """The robots in the world that are idle now."""
        return frozenset(self.idles)

    def keep(self, task: asyncio.Task[Any], *, finish: bool = False) -> None:
        """Own ``task`` (a transport's reader, a snapshot being sent): :meth:`aclose` cancels
        it, or with ``finish`` lets it end (a snapshot under way is still sent)."""
        self._background.add(task)
        task.add_done_callback(self._background.discard)
        if finish:
            self._finish.add(task)
            task.add_done_callback(self._finish.discard)

    # -- the calls ----------------------------------------------------------------------------

    async def join(self, robot: str, spec: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Add ``robot``; returns ``{"spec", "readings"}`` once it is in the world."""
        if robot in self.joins:  # a repeated join (a retry): the same answer
            return await asyncio.shield(self.joins[robot][1])
        if robot in self._early:
            return await asyncio.shield(self._early[robot])
        st = self.stepper
        if robot in st.robots():
            return {"spec": st.spec_of(robot), "readings": self.current(robot)}
        prepared = st.prepare(robot, spec)
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self.joins[robot] = (prepared, future)
        self.schedule.joined(robot)
        # shielded: a caller that gives up must not take a retry's answer down
        return await asyncio.shield(future)

    def submit(self, robot: str, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Hand in ``robot``'s command for ``tick``; the future gets its readings after it.

        Raises :class:`RobotDropped` if the robot is not in the world.
        """
        self._handing_in(robot, tick)
        return self.schedule.submit(robot, tick, command)

    def hand_in(self, robot: str, tick: int, command: Command) -> Readings | None:
        """Hand in ``robot``'s command for ``tick`` with no one waiting on it (a frame): its
        readings if ``tick`` is done already (a retry), else None (the tick's hooks tell)."""
        self._handing_in(robot, tick)
        return self.schedule.hand_in(robot, tick, command)

    async def step(self, robot: str, tick: int, command: Command) -> Readings:
        """Hand in ``robot``'s command for ``tick``; returns its readings after that tick."""
        waiter = self.submit(robot, tick, command)
        if waiter.done():  # this command completed the tick: still give others a turn
            await asyncio.sleep(0)
        # Shielded: a retry of this step shares the waiter, and a caller that gives up its
        # call (its task was cancelled) must not take the retry's readings down with it.
        return await asyncio.shield(waiter)

    def idle(self, robot: str, command: Command, at: int | None = None) -> Readings:
        """Mark ``robot`` idle: ``command`` (its stopped drive) stands for it at every tick and
        the door does not wait for it; returns its readings now. Idempotent (a retry). ``at``:
        the tick of the robot's readings as it went idle; its commands for the ticks before
        are owed, and with a control delay the world still waits for those that have not come
        yet (a command's frame can arrive after the call that idles the robot)."""
        self._check(robot)
        if robot not in self.idles:
            self.idles[robot] = dict(command)
            if at is not None:
                self.schedule.idled(robot, max(0, min(at, self.stepper.tick)))
            log.debug("robot %s idle at %s %d", robot, self.stepper.words[1], self.stepper.tick)
            self.schedule.pump()
        return self.current(robot)

    async def settled(self, robot: str) -> Readings:
        """``robot``'s readings once the world has every command it owes (see idle): at once
        without a control delay. Raises :class:`RobotDropped` if it leaves meanwhile."""
        await self.schedule.settled(robot)
        self._check(robot)
        return self.current(robot)

    def wake(self, robot: str) -> Readings:
        """``robot`` is not idle any more: from now on the door waits for its command, from
        the tick of the readings returned. Idempotent (a retry)."""
        self._check(robot)
        if self.idles.pop(robot, None) is not None:
            log.debug("robot %s awake at %s %d", robot, self.stepper.words[1], self.stepper.tick)
            self.schedule.woke(robot)
        return self.current(robot)

    async def watch(self, robot: str, on_readings: Callable[[Readings], None]) -> None:
        """Pass ``robot``'s readings to ``on_readings`` after every tick, until the robot is
        taken out of the world: then raise :class:`RobotDropped` (the in-process watch of an
        idle robot; a world process's robots watch its frames and its membership instead)."""
        self._check(robot)
        gone: asyncio.Future[None] = asyncio.get_running_loop().create_future()

        def seen(readings: Readings | None) -> None:
            if readings is not None:
                on_readings(readings)
            elif not gone.done():
                gone.set_result(None)

        self._watchers.setdefault(robot, []).append(seen)
        try:
            await gone
        finally:
            watchers = self._watchers.get(robot, [])
            if seen in watchers:
                watchers.remove(seen)
        raise RobotDropped(f"robot {robot!r} left the world")

    async def leave(self, robot: str) -> None:
        """Take ``robot`` out of the world."""
        self._remove(robot)
        self.schedule.pump()

    def drop(self, robot: str, why: str) -> None:
        """Take ``robot`` out now (e.g. its process left the team), with a log line."""
        if robot in self.stepper.robots() or robot in self.joins:
            tick = self.stepper.words[1]
            log.warning("robot %s %s: dropped at %s %d", robot, why, tick, self.stepper.tick)
            self.dropped.append(robot)
            self._remove(robot)
            self.schedule.pump()

    def status(self) -> dict[str, Any]:
        """The door's state for tools and tests: tick, robots, idle robots, dropped ones."""
        return {
            "tick": self.stepper.tick,
            "robots": sorted(self.stepper.robots()),
            "idle": sorted(self.idles),
            "dropped": list(self.dropped),
            "started": self.started,
        }

    async def aclose(self) -> None:
        """Stop the schedule, fail every pending call, end the tasks the door owns."""
        self.closed = True
        if self.started:
            gc.unfreeze()
        self.disarm()
        await self.schedule.aclose()
        for robot in [*self.stepper.robots(), *self.joins]:
            self._remove(robot)
        background = list(self._background)
        for task in background:
            if task not in self._finish:
                task.cancel()
        await asyncio.gather(*background, return_exceptions=True)

    # -- for the schedules ----------------------------------------------------------------------

    def busy(self) -> list[str]:
        """The robots in the world the door waits for (those not idle), in id order."""
        return sorted(r for r in self.stepper.robots() if r not in self.idles)

    def current(self, robot: str) -> Readings:
        """``robot``'s readings as of now, naming the tick its next command is for."""
        return self.schedule.current(robot)

    def waiter(self, robot: str) -> asyncio.Future[Readings]:
        """The future ``robot``'s caller waits on for its next readings (made if none)."""
        waiter = self._waiters.get(robot)
        if waiter is None:
            waiter = self._waiters[robot] = running_loop().create_future()
        return waiter

    def waiter_of(self, robot: str) -> asyncio.Future[Readings] | None:
        """The future ``robot``'s caller waits on, if any."""
        return self._waiters.get(robot)

    def answer(self, robot: str, readings: Readings) -> bool:
        """Give ``robot``'s waiter ``readings`` if one waits (False if none did)."""
        waiter = self._waiters.get(robot)
        if waiter is None or waiter.done():
            return False
        del self._waiters[robot]
        waiter.set_result(readings)
        return True

    def waiting(self) -> bool:
        """Whether any caller waits for readings."""
        return any(not w.done() for w in self._waiters.values())

    def run_tick(self, handed: Mapping[str, Command]) -> None:
        """Run one tick: the commands ``handed`` in, else idle robots' standing ones, in id
        order; then place the robots waiting to join, and answer everyone."""
        self.disarm()
        st = self.stepper
        robots = st.robots()
        commands = {
            r: handed[r] if r in handed else self.idles[r]
            for r in sorted(robots)
            if r in handed or r in self.idles
        }
        self.reported.clear()
        st.advance(commands)
        admitted = self.admit()
        st.sense()
        self.resolve(admitted, sensed=True)
        waiters, self._waiters = self._waiters, {}
        for robot, waiter in waiters.items():
            if not waiter.done() and robot in robots:
                waiter.set_result(st.readings(robot))
        self.told(commands)

    def told(self, commands: Mapping[str, Command]) -> None:
        """A tick is done: tell the watchers of idle robots, then the hooks."""
        st = self.stepper
        for robot, watchers in list(self._watchers.items()):
            if robot in st.robots():
                for seen in list(watchers):
                    seen(st.readings(robot))
        for hook in self.on_tick:
            hook(commands)

    def start(self) -> None:
        """The expected robots are in: place them and answer their joins.

        What exists now (the world, its bodies, the robots' links) lives as long as the run:
        it is moved out of the garbage collector's sight (``gc.freeze``), so that the full
        collections a run's allocations trigger scan what a tick made, not the whole world
        (at 200 robots in process they took a third of a tick: docs/physics.md); :meth:`aclose`
        hands it back (``gc.unfreeze``), so that a process running world after world frees
        each.
        """
        self.started = True
        gc.freeze()
        self.stepper.start()
        early, self._early = self._early, {}
        self.resolve([*early.items(), *self.admit()])
        self.schedule.started()

    def admit(self) -> list[_Join]:
        """Place the robots waiting to join, in id order (not sensed yet)."""
        if not self.joins or not (self.started or self.stepper.admits_early):
            return []
        joins, self.joins = self.joins, {}
        admitted = []
        for robot in sorted(joins):
            prepared, future = joins[robot]
            try:
                self.stepper.admit(robot, prepared)
            except ValueError as exc:
                if not future.done():
                    future.set_exception(exc)
                continue
            self.schedule.placed(robot)
            admitted.append((robot, future))
        return admitted

    def admit_now(self) -> None:
        """Place the robots waiting to join now, and answer them (at the start if not begun)."""
        admitted = self.admit()
        if self.started:
            self.resolve(admitted)
        else:  # in the world already, but its first readings are those at the start
            self._early.update(admitted)

    def resolve(self, admitted: list[_Join], *, sensed: bool = False) -> None:
        """Answer the joins of robots just placed (sensing first unless the tick ``sensed``)."""
        if admitted and not sensed:
            self.stepper.sense()
        st = self.stepper
        for robot, future in admitted:
            if not future.done() and robot in st.robots():
                future.set_result({"spec": st.spec_of(robot), "readings": st.readings(robot)})

    def arm(self) -> None:
        """Time the robots the tick waits for (see silence in the module)."""
        if self._deadline is None and not self.closed:
            self._deadline = asyncio.get_running_loop().call_later(self.timeout, self._expire)

    def disarm(self) -> None:
        """No robot is timed any more."""
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None

    def silent(self, robot: str, what: str) -> None:
        """``robot`` is silent past the timeout: drop it (``drop_silent``) or say so once."""
        tick, n = self.stepper.words[1], self.stepper.tick
        if not self.drop_silent:
            if robot not in self.reported:
                self.reported.add(robot)
                log.warning(
                    "waiting for robot %s: %s %d, %.1f s (%s it; it is still a member)",
                    robot,
                    tick,
                    n,
                    self.timeout,
                    what,
                )
            return
        log.warning("robot %s %s %s %d within %.1f s: dropped", robot, what, tick, n, self.timeout)
        self.dropped.append(robot)
        self._remove(robot)

    # -- inside -------------------------------------------------------------------------------

    def _check(self, robot: str) -> None:
        if robot not in self.stepper.robots():
            raise RobotDropped(f"robot {robot!r} is not in the world")

    def _handing_in(self, robot: str, tick: int) -> None:
        self._check(robot)
        if robot in self.idles and tick >= self.stepper.tick:  # a command wakes an idle robot
            self.wake(robot)

    def _expire(self) -> None:
        self._deadline = None
        if self.started:
            self.schedule.expire()

    def _remove(self, robot: str) -> None:
        self.stepper.remove(robot)
        self.schedule.removed(robot)
        self.idles.pop(robot, None)
        waiter = self._waiters.pop(robot, None)
        if waiter is not None and not waiter.done():
            waiter.set_exception(RobotDropped(f"robot {robot!r} left the world"))
        joining = self.joins.pop(robot, None)
        if joining is not None and not joining[1].done():
            joining[1].cancel()
        early = self._early.pop(robot, None)
        if early is not None and not early.done():
            early.cancel()
        for seen in self._watchers.pop(robot, []):
            seen(None)


def _schedule(
    stepper: Stepper, speed: float | None, period: float, turns: str, control_delay: int
) -> Schedule:
    if speed is not None and not speed > 0:
        raise ValueError("speed must be positive")
    if control_delay < 0:
        raise ValueError(f"control delay must be 0 or more ticks, got {control_delay}")
    if control_delay and (speed is not None or turns != "together"):
        raise ValueError("a control delay is for lock-step worlds whose robots act together")
    if control_delay:
        return Delayed(control_delay)
    if turns not in ("together", "sequential"):
        raise ValueError(f"turns must be together or sequential, got {turns!r}")
    if turns == "sequential":
        if speed is not None:
            raise ValueError("sequential turns run in lock-step only")
        if not isinstance(stepper, TurnStepper):
            raise TypeError(f"{type(stepper).__name__} cannot take sequential turns")
        return Turns(stepper)
    return Lockstep() if speed is None else RealTime(speed, period)
