"""The lock-step door of both worlds: robots join, hand in one command per tick, get readings.

Written once, against a small :class:`Stepper` protocol (admit a robot, advance one tick with
every robot's command, remove a robot); the pymunk world and the grid world are adapters to it.
What the door owns:

* **joins** — a robot asks to join with its settings; the stepper checks them at once (a bad
  spec fails the join at once) and places the robot at the next tick boundary (at once in a
  world with no robot to wait for), robots that wait together in id order. Before the first
  tick the door waits for ``expect`` robots: a stepper that ``admits_early`` (the pymunk world)
  puts each in the world at once and re-creates them all in id order when the last expected one
  is in (:meth:`Stepper.start`); the others (the grid) hold every join until then and place
  them all in id order. Either way every join is answered at the start, with the readings
  after it, whatever order the joins came in (over a network they race). A repeated join (a
  retry whose reply was lost) gets the same, shielded answer.
* **ticks** — in lock-step the world advances only when every robot in it that is not idle has
  handed in its command for the tick; commands are applied in id order. The first command a
  robot hands in for a tick is the one used: a later one for the same tick, or one for a tick
  already done, is a retry (it gets the readings after that tick, and is never applied).
  Waiters are shielded, so a caller that gives up its call (its task was cancelled) does not
  take a retry's answer down.
* **idle robots** — :meth:`LockstepDoor.idle` marks a robot idle with a standing command (its
  stopped drive): the door no longer waits for it, and applies that command for it at every
  tick until :meth:`LockstepDoor.wake`, from whose return on the door waits for the robot's
  command again, from the current tick. Idle robots stay in the world and keep getting
  readings (frames carry them, see ``sim_hw._process``). A tick needs at least one robot that
  is not idle: a lock-step world whose robots are all idle holds still (nothing runs, no
  timer), and is at a tick boundary, so a join is placed at once. Sequential turns skip idle
  robots. ``expect`` is unaffected: joins are still held until ``expect`` robots are in,
  whether or not those that are in are idle; an idle robot counts as one that is in.
* **silence** — when a robot is still missing ``timeout`` wall seconds after the first command
  of a tick came in, the door says so once (``waiting for robot X: tick N, K s``). With
  ``drop_silent`` (the default, for worlds in one process, where nothing else can tell that a
  robot's task is gone) it then drops the robot and the tick goes on without it. A world
  process sets ``drop_silent`` off (``sim_hw._process.serve``): there liveness decides, and a
  robot that is slow but still a member of the team is waited for however long it takes;
  :meth:`LockstepDoor.drop` takes out a robot whose process left the team.
* **modes** — ``speed`` set: real time, the world steps every ``period / speed`` wall seconds
  whoever has answered (a late robot keeps its last command; idle or not makes no
  difference); ``turns="sequential"``: a tick is one round in which robots act one at a time
  in id order, each perceiving just before its own turn (the :class:`TurnStepper` extension;
  Simonin et al.'s section 5.1).

Same seeds, world and commands: the same run, however long (in wall time) the world held
still in between. Costs: one dict entry and one future per robot per tick; the tick itself is
the stepper's.
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
    ``timeout`` wall seconds after a tick's first command, a missing robot is logged, and
    dropped if ``drop_silent`` (see the module). ``on_tick`` hooks are called after every tick
    with the commands applied.
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
        self.drop_silent = drop_silent
        self.speed = speed
        self.period = period
        self.turns = turns
        self.dropped: list[str] = []
        self.on_tick: list[Callable[[Mapping[str, Command]], None]] = []
        self._started = expect <= 0
        self._joins: dict[str, tuple[Any, asyncio.Future[dict[str, Any]]]] = {}
        # admitted early (before the start): answered at the start, with the readings then
        self._early: dict[str, asyncio.Future[dict[str, Any]]] = {}
        self._commands: dict[str, dict[str, Any]] = {}
        self._idle: dict[str, dict[str, Any]] = {}  # idle robot -> its standing command
        self._waiters: dict[str, asyncio.Future[Readings]] = {}
        self._watchers: dict[str, list[Callable[[Readings | None], None]]] = {}
        self._acted: set[str] = set()  # sequential: who has acted in this round
        self._reported: set[str] = set()  # robots said to be waited for in this tick
        self._deadline: asyncio.TimerHandle | None = None
        self._clock_task: asyncio.Task[None] | None = None
        self._background: set[asyncio.Task[Any]] = set()
        self._closed = False

    @property
    def lockstep(self) -> bool:
        """Whether the world waits for every robot (not real time)."""
        return self.speed is None

    @property
    def idle_robots(self) -> frozenset[str]:
        """The robots in the world that are idle now."""
        return frozenset(self._idle)

    def keep(self, task: asyncio.Task[Any]) -> None:
        """Own ``task`` (e.g. a transport's reader): :meth:`aclose` cancels it."""
        self._background.add(task)
        task.add_done_callback(self._background.discard)

    # -- the calls ----------------------------------------------------------------------------

    async def join(self, robot: str, spec: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Add ``robot``; returns ``{"spec", "readings"}`` once it is in the world."""
        if robot in self._joins:  # a repeated join (a retry): the same answer
            return await asyncio.shield(self._joins[robot][1])
        if robot in self._early:
            return await asyncio.shield(self._early[robot])
        st = self.stepper
        if robot in st.robots():
            return {"spec": st.spec_of(robot), "readings": self._current(robot)}
        prepared = st.prepare(robot, spec)
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._joins[robot] = (prepared, future)
        if not self.lockstep:
            self._ensure_clock()
            self._admit_now()
        elif not self._started:
            if st.admits_early:
                self._admit_now()
            count = len(st.robots()) + len(self._joins)
            if count >= self.expect:
                self._start()
            else:  # its join is answered at the start: say why it waits
                log.info("robot %s in: %d of %d, the world starts then", robot, count, self.expect)
        elif not self._busy():  # no robot to wait for: the world is at a tick boundary
            self._admit_now()
        # shielded: a caller that gives up must not take a retry's answer down
        return await asyncio.shield(future)

    def submit(self, robot: str, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Hand in ``robot``'s command for ``tick``; the future gets its readings after it.

        Raises :class:`RobotDropped` if the robot is not in the world.
        """
        if robot not in self.stepper.robots():
            raise RobotDropped(f"robot {robot!r} is not in the world")
        loop = asyncio.get_running_loop()
        waiter = self._waiters.get(robot)
        if robot in self._idle and tick >= self.stepper.tick:  # a command wakes an idle robot
            self.wake(robot)
        if self.turns == "sequential":
            return self._submit_turn(robot, tick, command, waiter)
        if self.lockstep and tick < self.stepper.tick:  # a retry whose reply was lost
            done: asyncio.Future[Readings] = loop.create_future()
            done.set_result(self.stepper.readings(robot))
            return done
        if not self.lockstep:
            self._commands[robot] = dict(command)  # real time: the latest command stands
        elif robot not in self._commands:  # the first command for a tick is the one used
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

    def idle(self, robot: str, command: Command) -> Readings:
        """Mark ``robot`` idle: ``command`` (its stopped drive) stands for it at every tick and
        the door does not wait for it; returns its readings now. Idempotent (a retry)."""
        if robot not in self.stepper.robots():
            raise RobotDropped(f"robot {robot!r} is not in the world")
        if robot not in self._idle:
            self._idle[robot] = dict(command)
            log.debug("robot %s idle at %s %d", robot, self.stepper.words[1], self.stepper.tick)
            self._maybe_step()
        return self._current(robot)

    def wake(self, robot: str) -> Readings:
        """``robot`` is not idle any more: from now on the door waits for its command, from
        the tick of the readings returned. Idempotent (a retry)."""
        if robot not in self.stepper.robots():
            raise RobotDropped(f"robot {robot!r} is not in the world")
        if self._idle.pop(robot, None) is not None:
            log.debug("robot %s awake at %s %d", robot, self.stepper.words[1], self.stepper.tick)
        return self._current(robot)

    async def watch(self, robot: str, on_readings: Callable[[Readings], None]) -> None:
        """Pass ``robot``'s readings to ``on_readings`` after every tick, until the robot is
        taken out of the world: then raise :class:`RobotDropped` (the in-process watch of an
        idle robot; a world process's robots watch its frames and its membership instead)."""
        if robot not in self.stepper.robots():
            raise RobotDropped(f"robot {robot!r} is not in the world")
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
        self._maybe_step()

    def drop(self, robot: str, why: str) -> None:
        """Take ``robot`` out now (e.g. its process left the team), with a log line."""
        if robot in self.stepper.robots() or robot in self._joins:
            tick = self.stepper.words[1]
            log.warning("robot %s %s: dropped at %s %d", robot, why, tick, self.stepper.tick)
            self.dropped.append(robot)
            self._remove(robot)
            self._maybe_step()

    def status(self) -> dict[str, Any]:
        """The door's state for tools and tests: tick, robots, idle robots, dropped ones."""
        return {
            "tick": self.stepper.tick,
            "robots": sorted(self.stepper.robots()),
            "idle": sorted(self._idle),
            "dropped": list(self.dropped),
            "started": self._started,
        }

    # -- stepping -----------------------------------------------------------------------------

    def _busy(self) -> list[str]:
        """The robots in the world the door waits for (those not idle), in id order."""
        return sorted(r for r in self.stepper.robots() if r not in self._idle)

    def _current(self, robot: str) -> Readings:
        """``robot``'s readings as of now, naming the tick its next command is for."""
        if self.turns == "sequential":
            return self._turns().sense_one(robot)
        return self.stepper.readings(robot)

    def _maybe_step(self) -> None:
        if not self.lockstep:
            return
        if self.turns == "sequential":
            self._pump()
            return
        busy = self._busy()
        if self._started and busy and all(r in self._commands for r in busy):
            self._tick()
        elif self._started and not busy and self._joins:  # no one to wait for: place them
            self._admit_now()

    def _tick(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        st = self.stepper
        robots = st.robots()
        # the first command handed in for the tick, else an idle robot's standing command
        commands = {
            r: self._commands[r] if r in self._commands else self._idle[r]
            for r in sorted(robots)
            if r in self._commands or r in self._idle
        }
        self._commands = {}
        self._reported.clear()
        st.advance(commands)
        admitted = self._admit()
        st.sense()
        self._resolve(admitted)
        waiters, self._waiters = self._waiters, {}
        for robot, waiter in waiters.items():
            if not waiter.done() and robot in robots:
                waiter.set_result(st.readings(robot))
        self._tell_watchers()
        for hook in self.on_tick:
            hook(commands)

    def _tell_watchers(self) -> None:
        st = self.stepper
        for robot, watchers in list(self._watchers.items()):
            if robot in st.robots():
                for seen in list(watchers):
                    seen(st.readings(robot))

    def _start(self) -> None:
        self._started = True
        self.stepper.start()
        early, self._early = self._early, {}
        self._resolve([*early.items(), *self._admit()])
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
        admitted = self._admit()
        if self._started:
            self._resolve(admitted)
        else:  # in the world already, but its first readings are those at the start
            self._early.update(admitted)

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
            todo = [n for n in self._busy() if n not in self._acted]
            if todo and todo[0] not in self._commands:
                self._silent(todo[0], "did not take its turn in")
            if self.drop_silent:
                self._pump()
            return
        for robot in self._busy():
            if robot not in self._commands:
                self._silent(robot, f"sent no {self.stepper.words[0]} for")
        self._maybe_step()

    def _silent(self, robot: str, what: str) -> None:
        """``robot`` is silent past the timeout: drop it (``drop_silent``) or say so once."""
        tick, n = self.stepper.words[1], self.stepper.tick
        if not self.drop_silent:
            if robot not in self._reported:
                self._reported.add(robot)
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

    def _remove(self, robot: str) -> None:
        self.stepper.remove(robot)
        self._acted.discard(robot)
        self._commands.pop(robot, None)
        self._idle.pop(robot, None)
        waiter = self._waiters.pop(robot, None)
        if waiter is not None and not waiter.done():
            waiter.set_exception(RobotDropped(f"robot {robot!r} left the world"))
        joining = self._joins.pop(robot, None)
        if joining is not None and not joining[1].done():
            joining[1].cancel()
        early = self._early.pop(robot, None)
        if early is not None and not early.done():
            early.cancel()
        for seen in self._watchers.pop(robot, []):
            seen(None)

    # -- sequential turns -----------------------------------------------------------------------

    def _turns(self) -> TurnStepper:
        st: Any = self.stepper
        return st  # type: ignore[no-any-return]

    def _submit_turn(
        self, robot: str, tick: int, command: Command, waiter: asyncio.Future[Readings] | None
    ) -> asyncio.Future[Readings]:
        now = self.stepper.tick
        pending = self._commands.get(robot)
        if tick < now or (tick == now and robot in self._acted):
            # a retry of an action already applied: the reply it waits for, or the latest
            if waiter is not None:
                return waiter
            done: asyncio.Future[Readings] = asyncio.get_running_loop().create_future()
            done.set_result(self.stepper.readings(robot))
            return done
        if pending is None or pending["_tick"] != tick:  # the first command for a tick stands
            self._commands[robot] = {**command, "_tick": tick}
        if waiter is None:
            waiter = self._waiters[robot] = asyncio.get_running_loop().create_future()
        self._pump()
        return waiter

    def _pump(self) -> None:
        """Apply commands in turn for as long as the robot whose turn it is has sent one."""
        st = self._turns()
        while self._started and st.robots():
            todo = [n for n in self._busy() if n not in self._acted]
            if not todo:
                if not self._acted:  # every robot is idle: the world holds still
                    break
                # the round is complete
                st.end_round()
                self._acted.clear()
                self._reported.clear()
                self._resolve(self._admit())
                st.begin_round()
                self._tell_watchers()
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
        if self._started and not self._busy() and not self._acted and self._joins:
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
