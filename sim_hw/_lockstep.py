"""The lock-step door of both worlds: robots join, hand in one command per tick, get readings.

Written once, against a small :class:`Stepper` protocol (admit a robot, advance one tick with
every robot's command, remove a robot); the pymunk world and the grid world are adapters to it.
What the door owns:

* **joins** — a robot asks to join with its settings; the stepper checks them at once (a bad
  spec fails the join at once) and places the robot at the next tick boundary (at once in an
  empty world), robots that wait together in id order. Before the first tick the door waits
  for ``expect`` robots: a stepper that ``admits_early`` (the pymunk world) puts each in the
  world at once and re-creates them all in id order when the last expected one is in
  (:meth:`Stepper.start`); the others (the grid) hold every join until then and place them all
  in id order. A repeated join (a retry
  whose reply was lost) gets the same, shielded answer.
* **ticks** — in lock-step the world advances only when every robot in it has handed in its
  command for the tick; commands are applied in id order. A command for a tick already done is
  a retry: it gets the current readings and is not applied again. Waiters are shielded, so a
  caller that gives up its call (its task was cancelled) does not take a retry's answer down.
* **drops** — a robot silent ``timeout`` wall seconds after the first command of a tick came in
  is dropped, with a log line, and the tick goes on without it; :meth:`LockstepDoor.drop` takes
  a robot out at once (its process left the team).
* **modes** — ``speed`` set: real time, the world steps every ``period / speed`` wall seconds
  whoever has answered (a late robot keeps its last command); ``turns="sequential"``: a tick is
  one round in which robots act one at a time in id order, each perceiving just before its own
  turn (the :class:`TurnStepper` extension; Simonin et al.'s section 5.1).

Same seeds, world and behaviours: the same run. Costs: one dict entry and one future per robot
per tick; the tick itself is the stepper's.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Collection, Mapping
from typing import Any, Generic, Protocol, TypeVar

from robots.hal import HardwareLost

log = logging.getLogger("sim_hw.lockstep")

Command = Mapping[str, Any]
"""A robot's command for a tick, as the world defines it (opaque to the door)."""
Readings = Any
"""A robot's readings after a tick, as the world defines them (opaque to the door)."""


class RobotDropped(HardwareLost, LookupError):
    """The robot is not (or no longer) in the world: it left, or it was dropped for silence."""


class Stepper(Protocol):
    """A world as the door drives it."""

    #: Whether a joining robot is in the world at once, before the first tick (see the module).
    admits_early: bool
    #: What the world calls a command and a tick, for log lines (e.g. "action", "round").
    words: tuple[str, str]

    @property
    def tick(self) -> int:
        """Ticks done."""

    def robots(self) -> Collection[str]:
        """Ids of the robots in the world."""

    def prepare(self, robot: str, spec: Mapping[str, Any] | None) -> Any:
        """Check a join's settings (raise ``ValueError`` to refuse it); returns what
        :meth:`admit` takes."""

    def admit(self, robot: str, prepared: Any) -> None:
        """Place ``robot`` (raise ``ValueError`` if it cannot be placed)."""

    def start(self) -> None:
        """The expected robots are in and nothing has moved yet."""

    def advance(self, commands: Mapping[str, Command]) -> None:
        """Advance one tick; ``commands`` holds every robot's command, in id order."""

    def sense(self) -> None:
        """Robots were placed or the world advanced: bring every robot's readings up to date."""

    def readings(self, robot: str) -> Readings:
        """``robot``'s readings as of now."""

    def spec_of(self, robot: str) -> dict[str, Any]:
        """The settings ``robot`` was admitted with (the join's answer)."""

    def remove(self, robot: str) -> None:
        """Take ``robot`` out (no error if it is not there)."""


class TurnStepper(Stepper, Protocol):
    """A stepper whose robots can also act one at a time (``turns="sequential"``)."""

    def act(self, robot: str, command: Command) -> None:
        """Apply ``robot``'s command now, in its turn."""

    def end_round(self) -> None:
        """Every robot has acted: close the round (the tick count goes up)."""

    def begin_round(self) -> None:
        """Robots waiting to join were placed: the new round begins."""

    def sense_one(self, robot: str) -> Readings:
        """``robot``'s perception just before its turn."""


S = TypeVar("S", bound=Stepper)


class LockstepDoor(Generic[S]):
    """Runs a :class:`Stepper` in lock-step (or real time) for the robots that join it.

    ``expect`` robots must join before the first tick (0: start at the first join).
    ``on_tick`` hooks are called after every tick with the commands applied.
    """

    def __init__(
        self,
        stepper: S,
        *,
        expect: int = 0,
        timeout: float = 2.0,
        speed: float | None = None,
        period: float = 0.1,
        turns: str = "together",
    ) -> None:
        if speed is not None and not speed > 0:
            raise ValueError("speed must be positive")
        if turns not in ("together", "sequential"):
            raise ValueError(f"turns must be together or sequential, got {turns!r}")
        if turns == "sequential" and speed is not None:
            raise ValueError("sequential turns run in lock-step only")
        self.stepper = stepper
        self.expect = expect
        self.timeout = timeout
        self.speed = speed
        self.period = period
        self.turns = turns
        self.dropped: list[str] = []
        self.on_tick: list[Callable[[Mapping[str, Command]], None]] = []
        self._started = expect <= 0
        self._joins: dict[str, tuple[Any, asyncio.Future[dict[str, Any]]]] = {}
        self._commands: dict[str, dict[str, Any]] = {}
        self._waiters: dict[str, asyncio.Future[Readings]] = {}
        self._acted: set[str] = set()  # sequential: who has acted in this round
        self._deadline: asyncio.TimerHandle | None = None
        self._clock_task: asyncio.Task[None] | None = None
        self._background: set[asyncio.Task[Any]] = set()
        self._closed = False

    @property
    def lockstep(self) -> bool:
        """Whether the world waits for every robot (not real time)."""
        return self.speed is None

    def keep(self, task: asyncio.Task[Any]) -> None:
        """Own ``task`` (e.g. a transport's reader): :meth:`aclose` cancels it."""
        self._background.add(task)
        task.add_done_callback(self._background.discard)

    # -- the three calls ----------------------------------------------------------------------

    async def join(self, robot: str, spec: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Add ``robot``; returns ``{"spec", "readings"}`` once it is in the world."""
        if robot in self._joins:  # a repeated join (a retry): the same answer
            return await asyncio.shield(self._joins[robot][1])
        st = self.stepper
        if robot in st.robots():
            return {"spec": st.spec_of(robot), "readings": st.readings(robot)}
        prepared = st.prepare(robot, spec)
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._joins[robot] = (prepared, future)
        if not self.lockstep:
            self._ensure_clock()
            self._admit_now()
        elif not self._started:
            if st.admits_early:
                self._admit_now()
            if len(st.robots()) + len(self._joins) >= self.expect:
                self._start()
        elif not st.robots():  # an empty world is always at a tick boundary
            self._admit_now()
        return await future

    def submit(self, robot: str, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Hand in ``robot``'s command for ``tick``; the future gets its readings after it.

        Raises :class:`RobotDropped` if the robot is not in the world.
        """
        if robot not in self.stepper.robots():
            raise RobotDropped(f"robot {robot!r} is not in the world")
        loop = asyncio.get_running_loop()
        waiter = self._waiters.get(robot)
        if self.turns == "sequential":
            return self._submit_turn(robot, tick, command, waiter)
        if self.lockstep and tick < self.stepper.tick:  # a retry whose reply was lost
            done: asyncio.Future[Readings] = loop.create_future()
            done.set_result(self.stepper.readings(robot))
            return done
        self._commands[robot] = dict(command)
        if waiter is None:
            waiter = self._waiters[robot] = loop.create_future()
        if not self.lockstep:
            self._ensure_clock()
            return waiter
        self._maybe_step()
        if not waiter.done() and self._deadline is None and self._started:
            self._deadline = loop.call_later(self.timeout, self._expire)
        return waiter

    async def step(self, robot: str, tick: int, command: Command) -> Readings:
        """Hand in ``robot``'s command for ``tick``; returns its readings after that tick."""
        waiter = self.submit(robot, tick, command)
        if waiter.done():  # this command completed the tick: still give others a turn
            await asyncio.sleep(0)
        # Shielded: a retry of this step shares the waiter, and a caller that gives up its
        # call (its task was cancelled) must not take the retry's readings down with it.
        return await asyncio.shield(waiter)

    async def leave(self, robot: str) -> None:
        """Take ``robot`` out of the world."""
        self._remove(robot)
        self._maybe_step()

    def drop(self, robot: str, why: str) -> None:
        """Take ``robot`` out now (e.g. its process left the team), with a log line."""
        if robot in self.stepper.robots() or robot in self._joins:
            tick = self.stepper.words[1]
            log.warning("robot %s %s: dropped at %s %d", robot, why, tick, self.stepper.tick)
            self.dropped.append(robot)
            self._remove(robot)
            self._maybe_step()

    # -- stepping -----------------------------------------------------------------------------

    def _maybe_step(self) -> None:
        if not self.lockstep:
            return
        if self.turns == "sequential":
            self._pump()
            return
        robots = self.stepper.robots()
        # commands only come from robots in the world, and leave with them: counting suffices
        if self._started and robots and len(self._commands) >= len(robots):
            self._tick()
        elif self._started and not robots and self._joins:  # the last robot left
            self._admit_now()

    def _tick(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        st = self.stepper
        robots = st.robots()
        commands = {r: self._commands[r] for r in sorted(self._commands) if r in robots}
        self._commands = {}
        st.advance(commands)
        admitted = self._admit()
        st.sense()
        self._resolve(admitted)
        waiters, self._waiters = self._waiters, {}
        for robot, waiter in waiters.items():
            if not waiter.done() and robot in robots:
                waiter.set_result(st.readings(robot))
        for hook in self.on_tick:
            hook(commands)

    def _start(self) -> None:
        self._started = True
        self.stepper.start()
        self._admit_now()
        if self.turns == "sequential":
            return
        self._maybe_step()
        if self._waiters and self._deadline is None:
            self._deadline = asyncio.get_running_loop().call_later(self.timeout, self._expire)

    def _admit(self) -> list[tuple[str, asyncio.Future[dict[str, Any]]]]:
        """Place the robots waiting to join, in id order (not sensed yet)."""
        if not self._joins or not (self._started or self.stepper.admits_early):
            return []
        joins, self._joins = self._joins, {}
        admitted = []
        for robot in sorted(joins):
            prepared, future = joins[robot]
            try:
                self.stepper.admit(robot, prepared)
            except ValueError as exc:
                if not future.done():
                    future.set_exception(exc)
                continue
            admitted.append((robot, future))
        return admitted

    def _admit_now(self) -> None:
        self._resolve(self._admit())

    def _resolve(self, admitted: list[tuple[str, asyncio.Future[dict[str, Any]]]]) -> None:
        if admitted:
            self.stepper.sense()
        st = self.stepper
        for robot, future in admitted:
            if not future.done() and robot in st.robots():
                future.set_result({"spec": st.spec_of(robot), "readings": st.readings(robot)})

    def _expire(self) -> None:
        self._deadline = None
        if not self._started:
            return
        if self.turns == "sequential":
            todo = [n for n in sorted(self.stepper.robots()) if n not in self._acted]
            if todo and todo[0] not in self._commands:
                self._drop_silent(todo[0], "did not take its turn in")
            self._pump()
            return
        for robot in sorted(set(self.stepper.robots()) - set(self._commands)):
            self._drop_silent(robot, f"sent no {self.stepper.words[0]} for")
        self._maybe_step()

    def _drop_silent(self, robot: str, what: str) -> None:
        log.warning(
            "robot %s %s %s %d within %.1f s: dropped",
            robot,
            what,
            self.stepper.words[1],
            self.stepper.tick,
            self.timeout,
        )
        self.dropped.append(robot)
        self._remove(robot)

    def _remove(self, robot: str) -> None:
        self.stepper.remove(robot)
        self._acted.discard(robot)
        self._commands.pop(robot, None)
        waiter = self._waiters.pop(robot, None)
        if waiter is not None and not waiter.done():
            waiter.set_exception(RobotDropped(f"robot {robot!r} left the world"))
        joining = self._joins.pop(robot, None)
        if joining is not None and not joining[1].done():
            joining[1].cancel()

    # -- sequential turns -----------------------------------------------------------------------

    def _turns(self) -> TurnStepper:
        st: Any = self.stepper
        return st  # type: ignore[no-any-return]

    def _submit_turn(
        self, robot: str, tick: int, command: Command, waiter: asyncio.Future[Readings] | None
    ) -> asyncio.Future[Readings]:
        now = self.stepper.tick
        if tick < now or (tick == now and robot in self._acted):
            # a retry of an action already applied: the reply it waits for, or the latest
            if waiter is not None:
                return waiter
            done: asyncio.Future[Readings] = asyncio.get_running_loop().create_future()
            done.set_result(self.stepper.readings(robot))
            return done
        self._commands[robot] = {**command, "_tick": tick}
        if waiter is None:
            waiter = self._waiters[robot] = asyncio.get_running_loop().create_future()
        self._pump()
        return waiter

    def _pump(self) -> None:
        """Apply commands in turn for as long as the robot whose turn it is has sent one."""
        st = self._turns()
        while self._started and st.robots():
            todo = [n for n in sorted(st.robots()) if n not in self._acted]
            if not todo:  # the round is complete
                st.end_round()
                self._acted.clear()
                self._resolve(self._admit())
                st.begin_round()
                for hook in self.on_tick:
                    hook({})
                continue
            robot = todo[0]
            self._offer(robot)
            command = self._commands.get(robot)
            if command is None or command["_tick"] != st.tick:
                break
            del self._commands[robot]
            command.pop("_tick")
            st.act(robot, command)
            self._acted.add(robot)
        if self._started and not st.robots() and self._joins:
            self._resolve(self._admit())
        self._rearm()

    def _offer(self, robot: str) -> None:
        """It is ``robot``'s turn: its perception is ready; answer its previous command."""
        waiter = self._waiters.get(robot)
        pending = self._commands.get(robot)
        if (
            waiter is None
            or waiter.done()
            or (pending is not None and pending["_tick"] == self.stepper.tick)
        ):
            return
        del self._waiters[robot]
        waiter.set_result(self._turns().sense_one(robot))

    def _rearm(self) -> None:
        """Time the robot whose turn it is, if anyone waits on it."""
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        if any(not w.done() for w in self._waiters.values()):
            self._deadline = asyncio.get_running_loop().call_later(self.timeout, self._expire)

    # -- real time ------------------------------------------------------------------------------

    def _ensure_clock(self) -> None:
        if self._clock_task is None and not self._closed:
            self._clock_task = asyncio.get_running_loop().create_task(self._run_clock())

    async def _run_clock(self) -> None:
        assert self.speed is not None
        period = self.period / self.speed
        next_at = time.monotonic()
        while True:
            next_at += period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))
            if self.stepper.robots():
                self._tick()
            else:
                next_at = time.monotonic()

    async def aclose(self) -> None:
        """Stop the real-time clock and fail every pending call."""
        self._closed = True
        if self._deadline is not None:
            self._deadline.cancel()
        if self._clock_task is not None:
            self._clock_task.cancel()
            try:
                await self._clock_task
            except asyncio.CancelledError:
                task = asyncio.current_task()
                if task is not None and task.cancelling():
                    raise
        for robot in [*self.stepper.robots(), *self._joins]:
            self._remove(robot)
        background = list(self._background)
        for task in background:
            task.cancel()
        await asyncio.gather(*background, return_exceptions=True)
