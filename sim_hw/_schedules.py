"""When the lock-step door ticks and what a tick applies: lock-step, real time, sequential turns.

A schedule is bound to one door (``sim_hw._lockstep``), which owns joins, idle robots, drops,
silence and answers; the schedule owns the commands handed in and decides, as they come (or
as time passes), when a tick runs. The three ways of ticking are described in the door's
module docstring.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import TYPE_CHECKING, Any

from ._types import Command, Readings, TurnStepper

if TYPE_CHECKING:
    from ._lockstep import LockstepDoor

log = logging.getLogger("sim_hw.lockstep")


class Schedule:
    """The lock-step schedule's behaviour where the others share it; each overrides the rest.

    ``lockstep`` says whether the door waits for every robot, ``turns`` whether robots act
    together or one at a time.
    """

    lockstep = True
    turns = "together"

    def __init__(self) -> None:
        self.commands: dict[str, dict[str, Any]] = {}  # robot -> its command for the tick
        self._door: LockstepDoor[Any] | None = None

    @property
    def door(self) -> LockstepDoor[Any]:
        """The door this schedule runs."""
        assert self._door is not None, "a schedule runs once it is bound to a door"
        return self._door

    def bind(self, door: LockstepDoor[Any]) -> None:
        """Run ``door`` (once, when it is made)."""
        self._door = door

    def joined(self, robot: str) -> None:
        """``robot`` asked to join: place it when the world is at a tick boundary (before the
        start, when the expected robots are in)."""
        door = self.door
        st = door.stepper
        if not door.started:
            if st.admits_early:
                door.admit_now()
            count = len(st.robots()) + len(door.joins)
            if count >= door.expect:
                door.start()
            else:  # its join is answered at the start: say why it waits
                log.info("robot %s in: %d of %d, the world starts then", robot, count, door.expect)
        elif not door.busy():  # no robot to wait for: the world is at a tick boundary
            door.admit_now()

    def take(self, robot: str, tick: int, command: Command) -> bool:
        """Keep ``robot``'s command for ``tick``; False if ``tick`` is done (a retry)."""
        if tick < self.door.stepper.tick:  # a retry whose reply was lost
            return False
        self.commands.setdefault(robot, dict(command))  # the first command for a tick stands
        return True

    def submit(self, robot: str, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Hand in a command for a caller: the future gets the readings after the tick."""
        door = self.door
        if not self.take(robot, tick, command):
            done: asyncio.Future[Readings] = asyncio.get_running_loop().create_future()
            done.set_result(door.stepper.readings(robot))
            return done
        waiter = door.waiter(robot)
        self.taken()
        return waiter

    def hand_in(self, robot: str, tick: int, command: Command) -> Readings | None:
        """Hand in a command no one waits on (see :meth:`LockstepDoor.hand_in`)."""
        if not self.take(robot, tick, command):
            return self.door.stepper.readings(robot)
        self.taken()
        return None

    def taken(self) -> None:
        """A command was kept: tick if it was the last one missing, else time the others."""
        self.pump()
        if self.commands and self.door.started:  # the tick still waits for someone
            self.door.arm()

    def pump(self) -> None:
        """Run the tick if every robot that is not idle handed in its command; with no robot
        to wait for, place the robots waiting to join."""
        door = self.door
        if not door.started:
            return
        commands = self.commands
        # counting first: the sorted scan runs once a tick, not once a command
        waited = len(door.stepper.robots()) - len(door.idles)
        if waited > 0 and len(commands) >= waited and all(r in commands for r in door.busy()):
            self.commands = {}
            door.run_tick(commands)
        elif door.joins and not door.busy():
            door.admit_now()

    def started(self) -> None:
        """The world started: commands handed in before may complete the first tick."""
        self.pump()
        if self.commands:
            self.door.arm()

    def expire(self) -> None:
        """The timeout passed with robots missing: tell of (or drop) each, then go on."""
        door = self.door
        for robot in door.busy():
            if robot not in self.commands:
                door.silent(robot, f"sent no {door.stepper.words[0]} for")
        self.pump()

    def current(self, robot: str) -> Readings:
        """``robot``'s readings as of now."""
        return self.door.stepper.readings(robot)

    def removed(self, robot: str) -> None:
        """``robot`` left the world: forget its command."""
        self.commands.pop(robot, None)

    def placed(self, robot: str) -> None:
        """``robot`` was placed in the world (nothing to do here)."""

    def idled(self, robot: str, at: int) -> None:
        """``robot`` is idle from tick ``at``: its commands for the ticks before are owed
        (nothing to do here: the world cannot be past them)."""

    async def settled(self, robot: str) -> None:
        """Return once the world has every command ``robot`` owes (see idled): at once here."""

    def woke(self, robot: str) -> None:
        """``robot`` is not idle any more (nothing to do here)."""

    async def aclose(self) -> None:
        """The door closes."""


class Lockstep(Schedule):
    """A tick once every robot that is not idle has handed in its command (the default)."""


class RealTime(Schedule):
    """A tick every ``period / speed`` wall seconds, whoever has answered; the latest command
    handed in for a robot stands."""

    lockstep = False

    def __init__(self, speed: float, period: float) -> None:
        super().__init__()
        self.speed, self.period = speed, period
        self._clock: asyncio.Task[None] | None = None

    def joined(self, robot: str) -> None:
        """Placed at once (the clock does not wait for it)."""
        self._ensure_clock()
        self.door.admit_now()

    def take(self, robot: str, tick: int, command: Command) -> bool:
        """The latest command stands, whatever tick it names."""
        self.commands[robot] = dict(command)
        return True

    def taken(self) -> None:
        """The clock ticks, not the commands."""
        self._ensure_clock()

    def pump(self) -> None:
        """Nothing: ticks come from the clock."""

    def _ensure_clock(self) -> None:
        if self._clock is None and not self.door.closed:
            self._clock = asyncio.get_running_loop().create_task(self._run())

    async def _run(self) -> None:
        door = self.door
        period = self.period / self.speed
        next_at = time.monotonic()
        while True:
            next_at += period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))
            if door.stepper.robots():
                commands, self.commands = self.commands, {}
                door.run_tick(commands)
            else:
                next_at = time.monotonic()

    async def aclose(self) -> None:
        """Stop the clock."""
        if self._clock is None:
            return
        self._clock.cancel()
        try:
            await self._clock
        except asyncio.CancelledError:
            task = asyncio.current_task()
            if task is not None and task.cancelling():
                raise


class Turns(Schedule):
    """A round in which robots that are not idle act one at a time in id order, each perceiving
    just before its turn; a robot's command waits for its turn."""

    turns = "sequential"

    def __init__(self, stepper: TurnStepper) -> None:
        super().__init__()
        self.stepper = stepper
        self.pending: dict[str, tuple[int, dict[str, Any]]] = {}  # robot -> (tick, command)
        self.acted: set[str] = set()  # who has acted in this round

    def submit(self, robot: str, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Keep the command for its turn; a retry of one applied gets the reply it waits for."""
        door = self.door
        now = self.stepper.tick
        if tick < now or (tick == now and robot in self.acted):
            waiter = door.waiter_of(robot)
            if waiter is not None:
                return waiter
            done: asyncio.Future[Readings] = asyncio.get_running_loop().create_future()
            done.set_result(self.stepper.readings(robot))
            return done
        pending = self.pending.get(robot)
        if pending is None or pending[0] != tick:  # the first command for a tick stands
            self.pending[robot] = (tick, dict(command))
        waiter = door.waiter(robot)
        self.pump()
        return waiter

    def hand_in(self, robot: str, tick: int, command: Command) -> Readings | None:
        """Turns take no frames: every command is a call."""
        raise RuntimeError("sequential turns take commands by call only")

    def pump(self) -> None:
        """Apply commands in turn for as long as the robot whose turn it is has sent one."""
        door, st = self.door, self.stepper
        while door.started and st.robots():
            todo = [n for n in door.busy() if n not in self.acted]
            if not todo:
                if not self.acted:  # every robot is idle: the world holds still
                    break
                self._end_round()
                continue
            robot = todo[0]
            self._offer(robot)
            pending = self.pending.get(robot)
            if pending is None or pending[0] != st.tick:
                break
            del self.pending[robot]
            st.act(robot, pending[1])
            self.acted.add(robot)
        if door.started and not door.busy() and not self.acted and door.joins:
            door.resolve(door.admit())
        self._rearm()

    def _end_round(self) -> None:
        door, st = self.door, self.stepper
        st.end_round()
        self.acted.clear()
        door.reported.clear()
        door.resolve(door.admit())
        st.begin_round()
        door.told({})

    def _offer(self, robot: str) -> None:
        """It is ``robot``'s turn: its perception is ready; answer its previous command."""
        pending = self.pending.get(robot)
        if pending is not None and pending[0] == self.stepper.tick:
            return
        waiter = self.door.waiter_of(robot)
        if waiter is not None and not waiter.done():
            self.door.answer(robot, self.stepper.sense_one(robot))

    def _rearm(self) -> None:
        """Time the robot whose turn it is, if anyone waits on it."""
        self.door.disarm()
        if self.door.waiting():
            self.door.arm()

    def started(self) -> None:
        """Nothing: the first turn comes with the first command."""

    def expire(self) -> None:
        """The robot whose turn it is did not take it: tell of (or drop) it."""
        door = self.door
        todo = [n for n in door.busy() if n not in self.acted]
        if todo and todo[0] not in self.pending:
            door.silent(todo[0], "did not take its turn in")
        if door.drop_silent:
            self.pump()

    def current(self, robot: str) -> Readings:
        """``robot``'s perception as of now (just before its turn)."""
        return self.stepper.sense_one(robot)

    def removed(self, robot: str) -> None:
        """``robot`` left the world: forget its command and its turn."""
        self.acted.discard(robot)
        self.pending.pop(robot, None)
