"""The world's clock and its door: robots join, send one command per tick, get readings back.

A :class:`WorldServer` owns a :class:`World` and decides when it steps:

* **lock-step** — the world advances one control tick only when every robot in it has sent its
  command for that tick; simulated time runs as fast as the slowest robot. With ``expect`` N,
  robots that join are in the world at once (their join returns) but the first tick waits until
  N are in; then they are re-created in id order, so the run does not depend on the order they
  came in — their first readings (from the join) may, so a deterministic robot ticks once before
  its first decision. Later joiners enter at tick boundaries, in id order. Commands are applied
  in robot-id order. Same seed, world and behaviours: the same run. A robot that has not
  answered ``timeout`` wall seconds after the first command of a tick arrived is dropped, with a
  log line, and the tick goes on without it.
* **real time** — the world steps every ``TICK / speed`` wall seconds whoever has answered; a
  robot that is late keeps its previous command.

``join``, ``step`` and ``leave`` are the three calls a robot makes; the in-process backend awaits
them directly and the world process exports them over zenoh.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import time
from collections.abc import Awaitable, Callable
from dataclasses import asdict
from typing import Any

from ._spec import RobotSpec
from ._world import TICK, Command, Readings, World
from ._worldfile import parse_robot

log = logging.getLogger("sim_hw.server")

Snapshot = dict[str, Any]


class RobotDropped(LookupError):
    """The robot is not (or no longer) in the world: it left, or it was dropped for silence."""


class WorldServer:
    """Runs a :class:`World` in lock-step or in (scaled) real time for robots that join it.

    ``expect`` robots must join before a lock-step world starts (0: start at the first join).
    ``on_snapshot(snapshot)`` is called every ``snapshot_every`` ticks (0: never); it may be a
    coroutine function (the world process wires it to ``node.broadcast``). ``on_tick(world,
    commands)`` is called after every tick (a recorder).
    """

    def __init__(
        self,
        world: World,
        *,
        lockstep: bool = True,
        speed: float = 1.0,
        expect: int = 0,
        timeout: float = 2.0,
        snapshot_every: int = 0,
        on_snapshot: Callable[[Snapshot], Any] | None = None,
        on_tick: Callable[[World, dict[str, Command]], None] | None = None,
    ) -> None:
        if speed <= 0:
            raise ValueError("speed must be positive")
        self.world = world
        self.lockstep = lockstep
        self.speed = speed
        self.expect = expect
        self.timeout = timeout
        self.snapshot_every = snapshot_every
        self.on_snapshot = on_snapshot
        self.on_tick = on_tick
        self.dropped: list[str] = []
        self._started = expect <= 0
        self._joins: dict[str, tuple[RobotSpec, asyncio.Future[dict[str, Any]]]] = {}
        self._commands: dict[str, Command] = {}
        self._waiters: dict[str, asyncio.Future[Readings]] = {}
        self._deadline: asyncio.TimerHandle | None = None
        self._clock_task: asyncio.Task[None] | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        self._closed = False

    # -- the three calls ----------------------------------------------------------------------

    async def join(self, robot: str, spec: dict[str, Any] | None = None) -> dict[str, Any]:
        """Add ``robot`` (settings in ``spec`` override the world's); returns ``{"spec",
        "readings"}`` once it is in the world. Joining again (a retry) gives the same answer."""
        if robot in self._joins:  # a repeated join (a retry): the same answer
            return await asyncio.shield(self._joins[robot][1])
        if robot in self.world.robots:
            return {
                "spec": asdict(self.world.robots[robot].parts.spec),
                "readings": self.world.readings(robot),
            }
        base = self.world.spec.robots.get(robot, self.world.spec.robot)
        resolved = parse_robot(spec or {}, base, f"join({robot})")
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._joins[robot] = (resolved, future)
        if not self.lockstep:
            self._ensure_clock()
            self._admit()
        elif not self._started:
            self._admit()
            if len(self.world.robots) >= self.expect:
                self._start()
        elif not self.world.robots:
            self._admit()
        return await future

    async def step(self, robot: str, tick: int, command: Command) -> Readings:
        """Hand in ``robot``'s command for tick ``tick``; returns its readings after that tick.

        In lock-step, a command for a tick that is already done is a retry whose reply was
        lost: it gets the current readings and is not applied again.
        """
        if robot not in self.world.robots:
            raise RobotDropped(f"robot {robot!r} is not in the world")
        if self.lockstep and tick < self.world.tick:
            return self.world.readings(robot)
        self._commands[robot] = command
        waiter = self._waiters.get(robot)
        if waiter is None:
            waiter = asyncio.get_running_loop().create_future()
            self._waiters[robot] = waiter
        if self.lockstep:
            self._maybe_step()
            if waiter.done():  # this command completed the tick: still give others a turn
                await asyncio.sleep(0)
            elif self._deadline is None and self._started:
                loop = asyncio.get_running_loop()
                self._deadline = loop.call_later(self.timeout, self._expire)
        else:
            self._ensure_clock()
        # Shielded: a retry of this step shares the waiter, and a caller that gives up its
        # call (its task was cancelled) must not take the retry's readings down with it.
        return await asyncio.shield(waiter)

    async def leave(self, robot: str) -> None:
        """Take ``robot`` out of the world."""
        self._remove(robot)
        if self.lockstep:
            self._maybe_step()

    def drop(self, robot: str, why: str) -> None:
        """Take ``robot`` out now (e.g. its process left the team), with a log line."""
        if robot in self.world.robots or robot in self._joins:
            log.warning("robot %s %s: dropped", robot, why)
            self.dropped.append(robot)
            self._remove(robot)
            if self.lockstep:
                self._maybe_step()

    # -- stepping -----------------------------------------------------------------------------

    def _maybe_step(self) -> None:
        # commands only come from robots in the world, and leave with them: counting suffices
        robots = self.world.robots
        if self._started and robots and len(self._commands) >= len(robots):
            self._tick()

    def _tick(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        commands = {r: self._commands[r] for r in sorted(self._commands) if r in self.world.robots}
        self._commands = {}
        for robot, command in commands.items():
            self.world.set_command(robot, command)
        self.world.step()
        if self.on_tick is not None:
            self.on_tick(self.world, commands)
        if self.snapshot_every and self.on_snapshot and self.world.tick % self.snapshot_every == 0:
            self._publish(self.world.snapshot())
        waiters, self._waiters = self._waiters, {}
        for robot, waiter in waiters.items():
            if not waiter.done() and robot in self.world.robots:
                waiter.set_result(self.world.readings(robot))
        self._admit()

    def _start(self) -> None:
        # Robots came in arrival order; re-create them in id order so that the run does not
        # depend on it (spawn points, solver order). Nothing has moved yet.
        self._started = True
        self.world.respawn_robots()
        self._maybe_step()
        if self._waiters and self._deadline is None:
            self._deadline = asyncio.get_running_loop().call_later(self.timeout, self._expire)

    def _admit(self) -> None:
        joins, self._joins = self._joins, {}
        for robot in sorted(joins):
            spec, future = joins[robot]
            readings = self.world.add_robot(robot, spec)
            if not future.done():
                future.set_result({"spec": asdict(spec), "readings": readings})

    def _expire(self) -> None:
        self._deadline = None
        if not self._started:
            return
        for robot in sorted(set(self.world.robots) - set(self._commands)):
            log.warning(
                "robot %s sent no command for tick %d within %.1f s: dropped",
                robot,
                self.world.tick,
                self.timeout,
            )
            self.dropped.append(robot)
            self._remove(robot)
        self._maybe_step()

    def _remove(self, robot: str) -> None:
        self.world.remove_robot(robot)
        self._commands.pop(robot, None)
        waiter = self._waiters.pop(robot, None)
        if waiter is not None and not waiter.done():
            waiter.set_exception(RobotDropped(f"robot {robot!r} left the world"))
        joining = self._joins.pop(robot, None)
        if joining is not None and not joining[1].done():
            joining[1].cancel()

    def _publish(self, snapshot: Snapshot) -> None:
        assert self.on_snapshot is not None
        result = self.on_snapshot(snapshot)
        if inspect.isawaitable(result):
            task = asyncio.ensure_future(_quietly(result))
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

    # -- real time ----------------------------------------------------------------------------

    def _ensure_clock(self) -> None:
        if self._clock_task is None and not self._closed:
            self._clock_task = asyncio.get_running_loop().create_task(self._run_clock())

    async def _run_clock(self) -> None:
        period = TICK / self.speed
        next_at = time.monotonic()
        while True:
            next_at += period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))
            if self.world.robots:
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
                if asyncio.current_task() and asyncio.current_task().cancelling():  # type: ignore[union-attr]
                    raise
        for robot in list(self.world.robots):
            self._remove(robot)
        for task in list(self._tasks):
            await task


async def _quietly(awaitable: Awaitable[Any]) -> None:
    try:
        await awaitable
    except Exception as exc:  # a lost snapshot must not stop the world
        log.debug("snapshot hook failed: %s", exc)
