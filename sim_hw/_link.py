"""The robot's link to its world: join, one exchange per tick, idling — in process or over zenoh.

Both wings' hardware is built on this. A backend joins and gets ``(joined, link)``: ``joined``
is the world's ``{"spec", "readings"}`` answer, ``link`` a :class:`WorldLink` (hand in the
command for a tick and wait for the readings after it; mark the robot idle or awake; watch an
idle robot's world). The robot's clock over a link is ``sim_hw._ticks.Ticks``.

* :func:`in_process` — the lock-step door in this process, awaited directly.
* :func:`remote` — a world process over a ``mover.Node``. Joins are calls. Ticks are frames
  when the world offers them (``joined["frames"]``): the robot broadcasts its command on the
  world's command topic, and the world answers every robot of a tick with one frame of
  readings on its readings topic, each robot's entry packed apart so that a robot decodes only
  its own (``sim_hw._frames``). This costs the world one signature per tick instead of one
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
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import TYPE_CHECKING, Any, Protocol

from robots.hal import HardwareLost

from ._frames import command_frame, own_entry, read_readings, topics
from ._types import Command, Readings, RobotDropped

if TYPE_CHECKING:
    from mover import Membership, Node, Subscription

    from ._lockstep import LockstepDoor

log = logging.getLogger("sim_hw.caller")

FRAME_WAIT = 1.0
"""Seconds a robot waits for its tick's frame before it asks with a call."""
FRAME_QUEUE = 64
"""Frames a robot keeps unread at most (one comes per tick)."""
MAX_LEAD = 100
"""The most ticks of control delay a world process takes (``--control-delay``) and a robot
accepts from one."""
WORLD_GRACE = 1.5
"""Seconds the world may be gone from the team (a missed lease on a loaded machine) before
a robot takes it for lost."""


class WorldLost(HardwareLost):
    """The world process is gone: it left the team and did not come back within WORLD_GRACE."""


class WorldLink(Protocol):
    """One robot's connection to its world (the door in process, or a world process)."""

    lead: int
    """The world's control delay: how many ticks it may run ahead of this robot's last
    command (0 in plain lock-step)."""

    async def exchange(self, tick: int, command: Command) -> Readings:
        """Hand in ``command`` for ``tick``; the readings after that tick."""
        ...

    async def idle(self, command: Command, at: int) -> Readings:
        """The world stops waiting for this robot; ``command`` stands for it at every tick.
        ``at``: the tick of the robot's readings (its commands for the ticks before are owed:
        see ``LockstepDoor.idle``); answered once the world has them all."""
        ...

    async def wake(self) -> Readings:
        """The world waits for this robot's commands again, from the tick of the readings."""
        ...

    async def watch(self, on_readings: Callable[[Readings], None]) -> None:
        """While idle: pass on the readings the world sends; raise HardwareLost when the world
        or this robot's body is gone (never returns otherwise)."""
        ...


class DoorLink:
    """A :class:`WorldLink` to a lock-step door in this process. Its :meth:`submit` hands a
    command in at once and gives the door's own future of the readings (a clock awaits that
    instead of running an exchange as a task: in a world of many robots in one process, the
    tasks and their hand-offs cost more than the physics)."""

    def __init__(self, door: LockstepDoor[Any], robot: str) -> None:
        self.door, self.robot = door, robot
        self.lead = door.control_delay

    def submit(self, tick: int, command: Command) -> asyncio.Future[Readings]:
        """Hand in ``command`` for ``tick`` now; the future gets the readings after it
        (RobotDropped, a HardwareLost, if the robot is not in the world)."""
        return self.door.submit(self.robot, tick, command)

    async def exchange(self, tick: int, command: Command) -> Readings:
        readings: Readings = await self.door.step(self.robot, tick, command)
        return readings

    async def idle(self, command: Command, at: int) -> Readings:
        self.door.idle(self.robot, command, at)
        return await self.door.settled(self.robot)

    async def wake(self) -> Readings:
        return self.door.wake(self.robot)

    async def watch(self, on_readings: Callable[[Readings], None]) -> None:
        await self.door.watch(self.robot, on_readings)


async def in_process(
    door: LockstepDoor[Any], robot_id: str, spec: Mapping[str, Any] | None = None
) -> tuple[dict[str, Any], WorldLink]:
    """Join ``door`` (a lock-step door in this process)."""
    joined: dict[str, Any] = await door.join(robot_id, spec)
    return joined, DoorLink(door, robot_id)


def world_caller(node: Node, world: str, call_timeout: float) -> Callable[..., Awaitable[Any]]:
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
            if world not in node.membership:
                try:
                    await node.membership.wait_for([world], timeout=WORLD_GRACE)
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

    def __init__(self, node: Node, robot: str, world: str, call_timeout: float) -> None:
        self.node, self.robot, self.world = node, robot, world
        self.call = world_caller(node, world, call_timeout)
        self.commands, self.readings_topic = topics(world)
        self.frames = node.subscribe(self.readings_topic, maxlen=FRAME_QUEUE)
        self.offered = False
        self.warm = False  # the first tick is a call: by its end the world has our subscription
        self.standing: Command = {}  # the command we idle with (asked again on a check)
        self.lead = 0  # the world's control delay, from its answer to the join

    async def join(self, spec: Mapping[str, Any] | None) -> dict[str, Any]:
        try:
            joined: dict[str, Any] = await self.call("join", self.robot, dict(spec or {}))
        except BaseException:
            self.frames.close()
            raise
        self.offered = bool(joined.get("frames"))
        lead = joined.get("lead", 0)
        if not isinstance(lead, int) or not 0 <= lead <= MAX_LEAD:
            self.frames.close()
            raise WorldLost(
                f"world {self.world!r} answered the join with a control delay of "
                f"{lead!r} ticks (0 to {MAX_LEAD})"
            )
        self.lead = lead
        if not self.offered:
            self.frames.close()
        return joined

    async def exchange(self, tick: int, command: Command) -> Readings:
        if self.warm:
            self.node.broadcast_nowait(
                self.commands, command_frame(self.robot, tick, command), reliable=True, express=True
            )
            got = await _own_entry(self.frames, self.world, self.robot, tick, FRAME_WAIT)
            if got is not None:
                return got
            log.info("%s: no frame for tick %d within %.1f s: asking", self.robot, tick, FRAME_WAIT)
        readings: Readings = await self.call("step", self.robot, tick, command)
        self.warm = self.offered
        return readings

    async def idle(self, command: Command, at: int) -> Readings:
        self.standing = dict(command)
        readings: Readings = await self.call("idle", self.robot, self.standing, at)
        return readings

    async def wake(self) -> Readings:
        readings: Readings = await self.call("wake", self.robot)
        return readings

    async def watch(self, on_readings: Callable[[Readings], None]) -> None:
        await _first_failure(self._watch_world(), self._watch_frames(on_readings))

    async def _watch_world(self) -> None:
        """Raise WorldLost once the world stays gone; after it was away, ask whether it still
        has our body (a world that dropped us, or restarted, says RobotDropped)."""
        team = self.node.membership
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
        while True:
            try:
                msg = await self.frames.get()
            except StopAsyncIteration:  # the node is closing: membership tells the rest
                await asyncio.Event().wait()
                return
            frame = read_readings(msg.data) if msg.sender == self.world else None
            if frame is None:
                continue
            readings = own_entry(frame, self.robot)
            if readings is not None:
                on_readings(readings)
            elif len(frame.entries) > 1:  # a tick's frame (not one robot's retry) without us
                await self.call("idle", self.robot, self.standing)  # still ours?


async def _gone(team: Membership, name: str) -> None:
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
    node: Node,
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
    frames: Subscription, world: str, robot_id: str, tick: int, wait: float
) -> Readings | None:
    """This robot's readings from the first frame after ``tick``, or None after ``wait`` s."""
    deadline = time.monotonic() + wait
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        try:
            msg = await frames.get(timeout=left)
        except (TimeoutError, StopAsyncIteration):
            return None
        frame = read_readings(msg.data) if msg.sender == world else None
        if frame is not None and frame.tick > tick:
            readings = own_entry(frame, robot_id)
            if readings is not None:
                return readings
