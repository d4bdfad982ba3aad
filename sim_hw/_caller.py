"""The robot's end of a world: join, one exchange per tick, idling — in process or over zenoh.

Both wings' hardware is built on this. A backend joins and gets ``(joined, link)``: ``joined``
is the world's ``{"spec", "readings"}`` answer, ``link`` a :class:`WorldLink` (hand in the
command for a tick and wait for the readings after it; mark the robot idle or awake; watch an
idle robot's world). :class:`Ticks` is the robot's clock over a link, shared by both wings.

* :func:`in_process` — the lock-step door in this process, awaited directly.
* :func:`remote` — a world process over a ``mover.Node``. Joins are calls. Ticks are frames
  when the world offers them (``joined["frames"]``): the robot broadcasts its command on the
  world's command topic, and the world answers every robot of a tick with one frame of
  readings on its readings topic, each robot's entry packed apart so that a robot decodes only
  its own (:func:`frame_topics`). This costs the world one signature per tick instead of one
  reply per robot. The first tick, and any tick whose frame does not come within
  ``FRAME_WAIT`` seconds (a lost frame, a world that dropped the robot, a world that is gone),
  is a call instead (``step``), which is idempotent: a retry for a tick already done gets the
  readings after it. Calls wait as long as the world is a member of the team (liveness, not a
  deadline: in lock-step a reply waits for the slowest robot); one that is not answered within
  ``call_timeout`` is asked again.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Mapping
from typing import Any, Protocol

from robots.hal import HardwareLost
from sim_hw._lockstep import Command, Readings, RobotDropped

log = logging.getLogger("sim_hw.caller")

FRAME_WAIT = 1.0
"""Seconds a robot waits for its tick's frame before it asks with a call."""
FRAME_QUEUE = 64
"""Frames a robot keeps unread at most (one comes per tick)."""
WORLD_GRACE = 1.5
"""Seconds the world may be gone from the team (a missed lease on a loaded machine) before
a robot takes it for lost."""


class WorldLost(HardwareLost):
    """The world process is gone: it left the team and did not come back within WORLD_GRACE."""


class WorldLink(Protocol):
    """One robot's connection to its world (the door in process, or a world process)."""

    async def exchange(self, tick: int, command: Command) -> Readings:
        """Hand in ``command`` for ``tick``; the readings after that tick."""
        ...

    async def idle(self, command: Command) -> Readings:
        """The world stops waiting for this robot; ``command`` stands for it at every tick."""
        ...

    async def wake(self) -> Readings:
        """The world waits for this robot's commands again, from the tick of the readings."""
        ...

    async def watch(self, on_readings: Callable[[Readings], None]) -> None:
        """While idle: pass on the readings the world sends; raise HardwareLost when the world
        or this robot's body is gone (never returns otherwise)."""
        ...


def frame_topics(world: str) -> tuple[str, str]:
    """The topics of a world's tick frames: (commands to it, readings from it)."""
    return (f"sim/{world}/commands", f"sim/{world}/readings")


class _DoorLink:
    """A :class:`WorldLink` to a lock-step door in this process."""

    def __init__(self, door: Any, robot: str) -> None:
        self.door, self.robot = door, robot

    async def exchange(self, tick: int, command: Command) -> Readings:
        readings: Readings = await self.door.step(self.robot, tick, command)
        return readings

    async def idle(self, command: Command) -> Readings:
        return self.door.idle(self.robot, command)

    async def wake(self) -> Readings:
        return self.door.wake(self.robot)

    async def watch(self, on_readings: Callable[[Readings], None]) -> None:
        await self.door.watch(self.robot, on_readings)


async def in_process(
    door: Any, robot_id: str, spec: Mapping[str, Any] | None = None
) -> tuple[dict[str, Any], WorldLink]:
    """Join ``door`` (a lock-step door in this process)."""
    joined: dict[str, Any] = await door.join(robot_id, spec)
    return joined, _DoorLink(door, robot_id)


def world_caller(node: Any, world: str, call_timeout: float) -> Callable[..., Awaitable[Any]]:
    """``call(procedure, *args)`` on the world process, for as long as it is alive.

    The world's calls (join, step, idle, wake) are idempotent. One that is not answered within
    ``call_timeout`` seconds is asked again while the world is a member (in lock-step a step
    waits for every robot, however slow). The world may look lost for a moment when the
    machine is overloaded (a missed lease): wait for it to be back and ask again; it is lost
    once it stays away WORLD_GRACE seconds, or keeps vanishing for ``call_timeout`` seconds.
    """
    from mover import CallTimeout, RemoteError, RobotLost, UnknownRobot

    def lost() -> WorldLost:
        return WorldLost(f"world {world!r} is gone (not in team {node.team_name!r})")

    async def call(procedure: str, *args: Any) -> Any:
        vanished: float | None = None  # when the world first failed a call by leaving
        while True:
            if world not in node.team:
                try:
                    await node.team.wait_for([world], timeout=WORLD_GRACE)
                except TimeoutError:
                    raise lost() from None
            try:
                return await node.call(world, procedure, *args, timeout=call_timeout)
            except CallTimeout:
                said = f"{procedure!r} on {world!r} not answered in {call_timeout:.0f} s"
                log.info("%s: %s: asking again (the world is alive)", node.name, said)
            except (RobotLost, UnknownRobot):
                vanished = time.monotonic() if vanished is None else vanished
                if time.monotonic() - vanished >= call_timeout:
                    raise lost() from None
                await asyncio.sleep(0.05)
            except RemoteError as exc:
                if exc.remote_type == "RobotDropped":  # the world no longer has our body
                    raise RobotDropped(exc.message) from None
                raise

    return call


class _RemoteLink:
    """A :class:`WorldLink` to a world process, over a node (see the module)."""

    def __init__(self, node: Any, robot: str, world: str, call_timeout: float) -> None:
        self.node, self.robot, self.world = node, robot, world
        self.call = world_caller(node, world, call_timeout)
        self.commands, self.readings_topic = frame_topics(world)
        self.frames = node.subscribe(self.readings_topic, maxlen=FRAME_QUEUE)
        self.offered = False
        self.warm = False  # the first tick is a call: by its end the world has our subscription
        self.standing: Command = {}  # the command we idle with (asked again on a check)

    async def join(self, spec: Mapping[str, Any] | None) -> dict[str, Any]:
        try:
            joined: dict[str, Any] = await self.call("join", self.robot, dict(spec or {}))
        except BaseException:
            self.frames.close()
            raise
        self.offered = bool(joined.get("frames"))
        if not self.offered:
            self.frames.close()
        return joined

    async def exchange(self, tick: int, command: Command) -> Readings:
        if self.warm:
            self.node.broadcast_nowait(
                self.commands, [self.robot, tick, command], reliable=True, express=True
            )
            got = await _own_entry(self.frames, self.world, self.robot, tick, FRAME_WAIT)
            if got is not None:
                return got
            log.info("%s: no frame for tick %d within %.1f s: asking", self.robot, tick, FRAME_WAIT)
        readings: Readings = await self.call("step", self.robot, tick, command)
        self.warm = self.offered
        return readings

    async def idle(self, command: Command) -> Readings:
        self.standing = dict(command)
        readings: Readings = await self.call("idle", self.robot, self.standing)
        return readings

    async def wake(self) -> Readings:
        readings: Readings = await self.call("wake", self.robot)
        return readings

    async def watch(self, on_readings: Callable[[Readings], None]) -> None:
        await _first_failure(self._watch_world(), self._watch_frames(on_readings))

    async def _watch_world(self) -> None:
        """Raise WorldLost once the world stays gone; after it was away, ask whether it still
        has our body (a world that dropped us, or restarted, says RobotDropped)."""
        team = self.node.team
        while True:
            await _gone(team, self.world)
            try:
                await team.wait_for([self.world], timeout=WORLD_GRACE)
            except TimeoutError:
                raise WorldLost(
                    f"world {self.world!r} is gone (not in team {self.node.team_name!r})"
                ) from None
            await self.call("idle", self.robot, self.standing)  # still ours?

    async def _watch_frames(self, on_readings: Callable[[Readings], None]) -> None:
        """Take our entry of every frame (the world keeps idle robots' readings up to date); a
        frame without it may mean the world dropped us: ask."""
        if not self.offered:
            await asyncio.Event().wait()  # no frames: membership alone tells
        from mover import unpack

        while True:
            try:
                msg = await self.frames.get()
            except StopAsyncIteration:  # the node is closing: membership tells the rest
                await asyncio.Event().wait()
                return
            data = msg.data
            if msg.sender != self.world or not isinstance(data, dict):
                continue
            entries = data.get("readings")
            if not isinstance(entries, dict):
                continue
            entry = entries.get(self.robot)
            if isinstance(entry, bytes):
                on_readings(unpack(entry))
            elif len(entries) > 1:  # a tick's frame (not one robot's retry) without us
                await self.call("idle", self.robot, self.standing)  # still ours?


async def _gone(team: Any, name: str) -> None:
    """Return once ``name`` is not a member of ``team`` (however long that takes)."""
    while name in team:
        with contextlib.suppress(TimeoutError):
            await team.wait_gone(name, timeout=3600.0)


async def _first_failure(*coros: Awaitable[None]) -> None:
    """Run ``coros`` together until the first ends; re-raise its exception, cancel the rest."""
    tasks = [asyncio.ensure_future(c) for c in coros]
    try:
        done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
        for task in done:
            task.result()
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)


async def remote(
    node: Any,
    robot_id: str,
    spec: Mapping[str, Any] | None = None,
    *,
    world: str,
    call_timeout: float = 30.0,
) -> tuple[dict[str, Any], WorldLink]:
    """Join the world process ``world`` over ``node``; ticks by frame where offered.

    ``call_timeout`` is how long one call waits for its answer before it is asked again (the
    world alive). The robot's id must be its node's name: the world drops the robot when that
    member leaves the team, and takes commands only from their sender.
    """
    link = _RemoteLink(node, robot_id, world, call_timeout)  # subscribes first: no race
    joined = await link.join(spec)
    return joined, link


async def _own_entry(
    frames: Any, world: str, robot_id: str, tick: int, wait: float
) -> Readings | None:
    """This robot's readings from the first frame after ``tick``, or None after ``wait`` s."""
    from mover import unpack

    deadline = time.monotonic() + wait
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        try:
            msg = await frames.get(timeout=left)
        except (TimeoutError, StopAsyncIteration):
            return None
        data = msg.data
        if msg.sender != world or not isinstance(data, dict):
            continue
        entry = data.get("readings", {}).get(robot_id) if data.get("tick", -1) > tick else None
        if isinstance(entry, bytes):
            readings: Readings = unpack(entry)
            return readings


class Ticks:
    """A robot's clock over a :class:`WorldLink`: its readings, one exchange at a time, idling.

    * ``tick(make)`` hands in ``make()`` (the command, built when the exchange starts) for the
      tick of the current readings and waits for the next readings. Concurrent callers share
      the exchange under way. The exchange runs as its own task: a caller that is cancelled
      leaves it to finish in the background (the world never sees half an exchange, and never
      a second command for the tick), and the next ``tick`` waits for it before its own.
    * ``idling(stop)``: the world neither waits for this robot nor lets it hold a tick back;
      ``stop()`` is the command that stands meanwhile (the stopped drive). The readings keep
      coming (frames carry idle robots' entries). Leaving is acknowledged by the world: on
      return, the world waits for this robot's command for the tick of ``readings``. A block
      left by cancellation does not wake the robot (it is going away); an exception does.
    * ``passed(t)`` returns once a command was handed in at a tick whose time is after ``t``.

    ``time_of(readings)`` is a tick's time (simulated seconds, or a round number); ``tick_of``
    its number; ``after(command, readings)`` runs when an exchange ends (in its task), before
    the new readings are seen.
    """

    def __init__(
        self,
        robot: str,
        link: WorldLink,
        readings: Readings,
        *,
        tick_of: Callable[[Readings], int],
        time_of: Callable[[Readings], float],
        after: Callable[[Command, Readings], None] | None = None,
    ) -> None:
        self.robot = robot
        self.readings = readings
        self._link = link
        self._tick_of, self._time_of, self._after = tick_of, time_of, after
        self._task: asyncio.Task[None] | None = None
        self._waiting = 0  # callers awaiting the exchange under way
        self._idle = False
        self._handed = -math.inf  # time of the readings the last command was handed in on
        self._hold: float | None = None  # no command on readings later than this (hold)
        self._lost: HardwareLost | None = None
        self._changed = asyncio.Event()

    @property
    def idle(self) -> bool:
        """Whether the robot is inside :meth:`idling`."""
        return self._idle

    def now(self) -> float:
        """The time of the current readings."""
        return self._time_of(self.readings)

    async def tick(self, make: Callable[[], Command]) -> None:
        """One exchange (shared with concurrent callers; see the class)."""
        if self._idle:
            raise RuntimeError(f"robot {self.robot!r} is idle (inside clock.idling()): no ticks")
        task = self._task
        if task is not None and not task.done() and self._waiting == 0:
            await self._finish(task)  # left by a cancelled caller: it goes first
            task = self._task
        while self._hold is not None and self.now() > self._hold and (task is None or task.done()):
            await self._wait_change()  # held (see hold): until released
            task = self._task
        if task is None or task.done():
            task = self._task = asyncio.get_running_loop().create_task(self._exchange(make))
            task.add_done_callback(_retrieved)
        self._waiting += 1
        try:
            await asyncio.shield(task)
        finally:
            self._waiting -= 1

    async def _finish(self, task: asyncio.Task[None]) -> None:
        """Wait for ``task`` to end; raise what it raised if it lost the hardware."""
        await asyncio.wait([task])
        failure = None if task.cancelled() else task.exception()
        if isinstance(failure, HardwareLost):
            raise failure

    async def _exchange(self, make: Callable[[], Command]) -> None:
        if self._lost is not None:
            raise self._lost
        command = make()
        self._handed = self.now()
        self._pulse()
        try:
            readings = await self._link.exchange(self._tick_of(self.readings), command)
        except HardwareLost as exc:
            self._lose(exc)
            raise
        if self._after is not None:
            self._after(command, readings)
        self.readings = readings
        self._pulse()

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)``: a tick waits
        (and may be cancelled there, having handed in nothing). A ``distributed_or`` in
        simulated time holds a member that is past the earliest finish until the decision, so
        that a loser stops on the same tick whatever the wall clock does."""
        self._hold = t
        self._pulse()

    async def passed(self, t: float) -> None:
        """Return once a command was handed in with readings of time ``t`` or later: this
        robot went on past ``t`` (a robot whose program stopped at ``t`` hands in nothing)."""
        while not self._handed >= t:
            if self._lost is not None:
                raise self._lost
            await self._wait_change()

    @contextlib.asynccontextmanager
    async def idling(self, stop: Callable[[], Command]) -> AsyncIterator[None]:
        """Be idle for the block (see the class); HardwareLost if the world is gone."""
        if self._idle:
            raise RuntimeError(f"robot {self.robot!r} is already idle")
        if self._task is not None and not self._task.done():
            await self._finish(self._task)  # the exchange under way ends first
        if self._lost is not None:
            raise self._lost
        self._idle = True
        try:
            self.readings = await self._guard(self._link.idle(stop()))
            watch = asyncio.get_running_loop().create_task(self._watch())
            awake = True
            try:
                yield
            except asyncio.CancelledError:
                # Going away (the process ends, or reconnects): no wake. Should this robot
                # tick again, its first command wakes it in the world (see the door).
                awake = False
                raise
            finally:
                watch.cancel()
                await asyncio.gather(watch, return_exceptions=True)
                if awake and self._lost is None:
                    self.readings = await self._guard(self._link.wake())
        finally:
            self._idle = False
            self._pulse()

    async def _watch(self) -> None:
        def seen(readings: Readings) -> None:
            if self._tick_of(readings) > self._tick_of(self.readings):
                self.readings = readings

        with contextlib.suppress(HardwareLost):  # _guard noted it: passed() raises it
            await self._guard(self._link.watch(seen))

    async def _guard(self, call: Awaitable[Readings | None]) -> Any:
        try:
            return await call
        except HardwareLost as exc:
            self._lose(exc)
            raise

    def _lose(self, exc: HardwareLost) -> None:
        if self._lost is None:
            self._lost = exc
        self._pulse()

    def _pulse(self) -> None:
        self._changed.set()
        self._changed = asyncio.Event()

    async def _wait_change(self) -> None:
        await self._changed.wait()


def _retrieved(task: asyncio.Task[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieved: the caller that awaited it, if any, was told
