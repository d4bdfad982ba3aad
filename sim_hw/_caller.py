"""The robot's end of a world: join, then one exchange per tick — in process or over zenoh.

Both wings' backends are built on this: a backend joins and gets ``(joined, exchange)``, where
``joined`` is the world's ``{"spec", "readings"}`` answer and ``exchange(tick, command) ->
readings`` hands in the command for a tick and waits for the readings after it.

* :func:`in_process` — the lock-step door in this process, awaited directly.
* :func:`remote` — a world process over a ``mover.Node``. Joins are calls. Ticks are frames
  when the world offers them (``joined["frames"]``): the robot broadcasts its command on the
  world's command topic, and the world answers every robot of a tick with one frame of
  readings on its readings topic, each robot's entry packed apart so that a robot decodes only
  its own (:func:`frame_topics`). This costs the world one signature per tick instead of one
  reply per robot. The first tick, and any tick whose frame does not come within
  ``FRAME_WAIT`` seconds (a lost frame, a world that dropped the robot, a world that is gone),
  is a call instead (``step``), which is idempotent: a retry for a tick already done gets the
  readings after it.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from robots.hal import HardwareLost
from sim_hw._lockstep import Command, Readings, RobotDropped

log = logging.getLogger("sim_hw.caller")

Exchange = Callable[[int, Command], Awaitable[Readings]]

FRAME_WAIT = 1.0
"""Seconds a robot waits for its tick's frame before it asks with a call."""
FRAME_QUEUE = 64
"""Frames a robot keeps unread at most (one comes per tick)."""
WORLD_GRACE = 1.5
"""Seconds the world may be gone from the team (a missed lease on a loaded machine) before
a robot takes it for lost."""


class WorldLost(HardwareLost):
    """The world process is gone: it left the team and did not come back within WORLD_GRACE."""


def frame_topics(world: str) -> tuple[str, str]:
    """The topics of a world's tick frames: (commands to it, readings from it)."""
    return (f"sim/{world}/commands", f"sim/{world}/readings")


async def in_process(
    door: Any, robot_id: str, spec: Mapping[str, Any] | None = None
) -> tuple[dict[str, Any], Exchange]:
    """Join ``door`` (a lock-step door in this process)."""
    joined: dict[str, Any] = await door.join(robot_id, spec)

    async def exchange(tick: int, command: Command) -> Readings:
        readings: Readings = await door.step(robot_id, tick, command)
        return readings

    return joined, exchange


def world_caller(node: Any, world: str, call_timeout: float) -> Callable[..., Awaitable[Any]]:
    """``call(procedure, *args)`` on the world process, asked again while it looks lost.

    The world may look lost for a moment when the machine is overloaded (a missed lease);
    its calls (join, step) are idempotent, so wait for it to be back and ask again, until
    ``call_timeout`` seconds have passed.
    """
    from mover import RemoteError, RobotLost, UnknownRobot

    def lost() -> WorldLost:
        return WorldLost(f"world {world!r} is gone (not in team {node.team_name!r})")

    async def call(procedure: str, *args: Any) -> Any:
        deadline = time.monotonic() + call_timeout
        while True:
            if world not in node.team:
                try:
                    await node.team.wait_for([world], timeout=WORLD_GRACE)
                except TimeoutError:
                    raise lost() from None
            left = deadline - time.monotonic()
            try:
                return await node.call(world, procedure, *args, timeout=max(left, 0.1))
            except (RobotLost, UnknownRobot):
                if time.monotonic() >= deadline:
                    raise lost() from None
                await asyncio.sleep(0.05)
            except RemoteError as exc:
                if exc.remote_type == "RobotDropped":  # the world no longer has our body
                    raise RobotDropped(exc.message) from None
                raise

    return call


async def remote(
    node: Any,
    robot_id: str,
    spec: Mapping[str, Any] | None = None,
    *,
    world: str,
    call_timeout: float = 30.0,
) -> tuple[dict[str, Any], Exchange]:
    """Join the world process ``world`` over ``node``; ticks by frame where offered.

    ``call_timeout`` must outlast the world's own drop timeout, since in lock-step a reply
    waits for every robot. The robot's id must be its node's name: the world drops the robot
    when that member leaves the team, and takes commands only from their sender.
    """
    call = world_caller(node, world, call_timeout)
    commands, readings_topic = frame_topics(world)
    frames = node.subscribe(readings_topic, maxlen=FRAME_QUEUE)  # before the join: no race
    try:
        joined: dict[str, Any] = await call("join", robot_id, dict(spec or {}))
    except BaseException:
        frames.close()
        raise
    if not joined.get("frames"):
        frames.close()
    warm = False  # the first tick is a call: by its end the world has seen our subscription

    async def exchange(tick: int, command: Command) -> Readings:
        nonlocal warm
        if warm:
            node.broadcast_nowait(commands, [robot_id, tick, command], reliable=True, express=True)
            got = await _own_entry(frames, world, robot_id, tick)
            if got is not None:
                return got
            log.info("%s: no frame for tick %d within %.1f s: asking", robot_id, tick, FRAME_WAIT)
        readings: Readings = await call("step", robot_id, tick, command)
        warm = bool(joined.get("frames"))
        return readings

    return joined, exchange


async def _own_entry(frames: Any, world: str, robot_id: str, tick: int) -> Readings | None:
    """This robot's readings from the first frame after ``tick``, or None after FRAME_WAIT."""
    from mover import unpack

    deadline = time.monotonic() + FRAME_WAIT
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
