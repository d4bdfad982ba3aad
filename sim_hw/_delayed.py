"""Lock-step with a control delay of K ticks: a command handed in for tick t applies at tick t + K.

Like a real robot's sense-to-act latency, and what lets a lock-step world run ahead of the
network's round trip: the world runs tick T once every robot it waits for has handed in its
command for tick T - K (ticks before K apply none), so it is up to K ticks ahead of the
robots, and a robot that hands in its command for tick t gets the readings after tick t at
once if the world is there already (the world keeps the last K + 1 ticks' readings). With
frames, each tick's frame carries every robot's entry, so that a robot finds the readings it
waits for in its queue. One round trip then carries K + 1 ticks instead of one.

Deterministic as lock-step is: the commands applied at a tick are those handed in for one
tick, in id order, whatever the wall clock did; a robot waits for the readings after its own
tick, never later ones. The world waits for a robot's commands from the tick it joined or
woke at (the ticks before apply its standing command: stopped, if it was idle).

A tick runs only if some robot's command asks for it: one due at it, or one handed in for it
or a later tick. So the ticks no awake robot's command is due at (after a wake or a join) do
not run at whichever call happens to come first (a timer, an idle), and once every robot idles
the world still applies the commands handed in before (else where it stopped, and so the tick
the robots wake at, hung on the order of the idles: docs/reproducible-runs.md).

Cost: the readings of K + 1 ticks (references to what the world built anyway) and a dict of
commands a tick.
"""

from __future__ import annotations

import asyncio
import logging
from collections import deque

from ._schedules import Schedule
from ._types import Command, Readings

log = logging.getLogger("sim_hw.lockstep")


class Delayed(Schedule):
    """Lock-step whose commands apply ``k`` ticks after the tick they were handed in for."""

    def __init__(self, k: int) -> None:
        super().__init__()
        if k < 1:
            raise ValueError(f"a control delay is a whole number of ticks from 1, got {k}")
        self.k = k
        self.queue: dict[int, dict[str, Command]] = {}  # tick -> robot -> its command
        self.since: dict[str, int] = {}  # robot -> the first tick whose command is waited for
        self.owed: dict[str, int] = {}  # idle robot -> the tick it idles from (see idled)
        self._paid: dict[str, asyncio.Future[None]] = {}  # owed robot -> its settled() wait
        # (tick, {robot: readings after it}), the last k + 1 ticks
        self.history: deque[tuple[int, dict[str, Readings]]] = deque(maxlen=k + 1)

    def take(self, robot: str, tick: int, command: Command) -> bool:
        """Keep ``robot``'s command for ``tick`` unless it is too late to apply; the first
        command for a tick stands. False if the world is past ``tick`` (the caller is answered
        from the readings kept)."""
        now: int = self.door.stepper.tick
        if tick >= now - self.k:  # it may still apply
            self.queue.setdefault(tick, {}).setdefault(robot, dict(command))
        return tick >= now

    def submit(self, robot: str, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Hand in a command; the future gets the readings after ``tick`` (at once if the
        world is past it)."""
        if not self.take(robot, tick, command):
            done: asyncio.Future[Readings] = asyncio.get_running_loop().create_future()
            done.set_result(self.after(robot, tick))
            self.taken()
            return done
        waiter = self.door.waiter(robot)
        self.taken()
        return waiter

    def hand_in(self, robot: str, tick: int, command: Command) -> Readings | None:
        """Hand in a command no one waits on: the readings after ``tick`` if the world is past
        it, else None."""
        done = None if self.take(robot, tick, command) else self.after(robot, tick)
        self.taken()
        return done

    def after(self, robot: str, tick: int) -> Readings:
        """``robot``'s readings after ``tick`` (those of now if they are no longer kept: a
        retry of long ago)."""
        for done, readings in self.history:
            if done == tick + 1 and robot in readings:
                return readings[robot]
        return self.door.stepper.readings(robot)

    def taken(self) -> None:
        """Tick for as long as the commands are in; time the robots missing."""
        self.pump()
        if self.door.started:
            self.door.arm()

    def pump(self) -> None:
        """Run every tick whose commands are in and that a command asks for (see the module;
        ticks before k apply none); with no robot to wait for, place the robots waiting to
        join."""
        door = self.door
        if not door.started:
            return
        st = door.stepper
        while not door.closed:
            need = st.tick - self.k
            due = len(self._waited(need)) if need >= 0 else 0
            if due > 0:
                # counting first: the scan runs once a tick, not once a command
                if len(self.queue.get(need, {})) < due or self._missing():
                    break
            elif not any(t >= need for t in self.queue):
                break  # no command due nor still to apply: nothing asks for this tick
            door.run_tick(self.queue.pop(need, {}))
            self.history.append((st.tick, {r: st.readings(r) for r in st.robots()}))
            self.since = {r: t for r, t in self.since.items() if t > need}
            self._settle({r: t for r, t in self.owed.items() if t > self._next()})
        if door.joins and not door.busy():
            door.admit_now()

    def placed(self, robot: str) -> None:
        """``robot`` was placed: its commands are waited for from the tick of its first
        readings."""
        self.since[robot] = self.door.stepper.tick

    def idled(self, robot: str, at: int) -> None:
        """``robot`` went idle on the readings of tick ``at``: its commands for the ticks before
        are still waited for (they may come after the call that idled it: frames and calls
        are not ordered), so that the ticks they apply at do not run on its standing command
        by the wall clock."""
        if at > self._next():  # (the ticks before the next to run are applied already)
            self.owed[robot] = at

    async def settled(self, robot: str) -> None:
        """Return once the world has every command ``robot`` owes (a command's frame may come
        after the call that idles the robot): a robot is idle only from then on, so that the
        world is at rest at the same tick whatever the wall clock did when the last member of
        a step goes idle, and the robots wake there."""
        if self.owed.get(robot, 0) > self._next():
            paid = self._paid.get(robot)
            if paid is None:
                paid = self._paid[robot] = asyncio.get_running_loop().create_future()
            await asyncio.shield(paid)

    def _settle(self, owed: dict[str, int]) -> None:
        """``owed`` is what the robots owe now: wake the waits of those that owe nothing."""
        self.owed = owed
        for robot in [r for r in self._paid if r not in owed]:
            paid = self._paid.pop(robot)
            if not paid.done():
                paid.set_result(None)

    def woke(self, robot: str) -> None:
        """``robot`` is awake again: its commands are waited for from now on."""
        self._settle({r: t for r, t in self.owed.items() if r != robot})
        self.since[robot] = self.door.stepper.tick

    def started(self) -> None:
        """The world started: nothing to run until a command asks for a tick."""
        self.pump()

    def expire(self) -> None:
        """The timeout passed with robots missing: tell of (or drop) each, then go on."""
        door = self.door
        for robot in self._missing():
            door.silent(robot, f"sent no {door.stepper.words[0]} for")
        self.pump()

    async def aclose(self) -> None:
        """The door closes: nothing more is owed (a robot waiting to idle is answered)."""
        self._settle({})

    def removed(self, robot: str) -> None:
        """``robot`` left the world: forget its commands."""
        self.since.pop(robot, None)
        self._settle({r: t for r, t in self.owed.items() if r != robot})
        for commands in self.queue.values():
            commands.pop(robot, None)

    def _next(self) -> int:
        """The tick whose commands the world applies next (none before tick 0)."""
        tick: int = self.door.stepper.tick
        return max(tick - self.k, 0)

    def _waited(self, need: int) -> list[str]:
        """The robots whose command for tick ``need`` the world waits for: those not idle that
        joined or woke by then, and idle ones that owe it (see idled); in id order."""
        idles = self.door.idles
        return [
            r
            for r in sorted(self.door.stepper.robots())
            if (r not in idles and self.since.get(r, need) <= need)
            or (r in idles and self.owed.get(r, 0) > need)
        ]

    def _missing(self) -> list[str]:
        """The robots whose command for the tick the world would run next is not in."""
        need = self.door.stepper.tick - self.k
        if need < 0:
            return []
        got = self.queue.get(need, {})
        return [r for r in self._waited(need) if r not in got]
