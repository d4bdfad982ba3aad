"""The world process of both worlds: a lock-step door exported over a mover node.

Robots call ``join(robot, spec)``, ``step(robot, tick, command)`` (in lock-step the reply comes
once every robot's command for the tick is in and the world has stepped), ``idle(robot,
command)`` and ``wake(robot)`` (the door stops and starts waiting for the robot), and
``leave(robot)``; tools call ``status()``. Liveness decides drops: the door waits for a robot
that is slow but still a member of the team however long it takes (it says so once per tick,
after ``--timeout`` seconds); a robot whose process leaves the team is dropped
(``team.on_gone``: only once it has stayed gone for a second, so a flapping link keeps its
body). A dropped robot rejoins when it comes back (the robot process reconnects on
``HardwareLost``). :func:`run_world_process` is the one main of ``mover world`` and ``mover
gridworld``.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
from collections.abc import Callable, Mapping
from typing import Any, Protocol, TypeVar

from mover import MoverError, Node, NodeConfig, TeamCredentials
from mover._endpoints import bound
from mover.cli import bounded, member_name, positive
from sim_hw._frames import read_command, readings_frame, topics
from sim_hw._link import MAX_LEAD
from sim_hw._lockstep import Command, LockstepDoor, RobotDropped

log = logging.getLogger("sim_hw.process")

COMMAND_QUEUE = 10_000
"""Command frames a world keeps unread at most."""

STATE_TOPIC = "world/state"
"""The team-wide topic on which a world process streams its snapshots."""


MAX_COUNT = 100_000
"""The most a count read from a command line may be (robots expected, rounds between snapshots)."""
MAX_RATE = 1000.0
"""The most a rate read from a command line may be (per simulated second)."""


count = bounded(int, 0, MAX_COUNT)
"""An argparse type: a whole number from 0 to MAX_COUNT."""
rate = bounded(float, 0.0, MAX_RATE)
"""An argparse type: a number from 0 to MAX_RATE."""
"""The most ticks of control delay a command line may ask for."""
control_delay = bounded(int, 0, MAX_LEAD)
"""An argparse type: a control delay in ticks, from 0 to MAX_LEAD."""


def add_world_arguments(
    p: argparse.ArgumentParser, *, name: str, timeout: float, tick: str, seed: str
) -> None:
    """The options every world process takes: ``--expect``, ``--timeout``, ``--seed``,
    ``--name``, ``--quit-when-empty`` (``tick`` names a tick, ``seed`` what the seed draws)."""
    p.add_argument(
        "--expect",
        type=count,
        default=0,
        metavar="N",
        help=f"lock-step: wait for N robots before the first {tick}",
    )
    p.add_argument(
        "--timeout",
        type=positive,
        default=timeout,
        metavar="S",
        help=f"lock-step: say which robot a {tick} waits for after S wall seconds (default "
        f"{timeout:g}); a robot is dropped only when its process leaves the team",
    )
    p.add_argument("--seed", type=int, default=0, help=f"seed of {seed}")
    p.add_argument(
        "--name",
        type=member_name,
        default=name,
        help=f"the world process's node name (default {name})",
    )
    p.add_argument(
        "--quit-when-empty",
        action="store_true",
        help="stop once robots have come and all have left",
    )


def ready_line(name: str, source: str, team: TeamCredentials, config: NodeConfig) -> str:
    """What a world process prints once it serves: where it is and how robots join it (the
    exact endpoints, ``:0`` resolved to the port zenoh chose, and the variables to set)."""
    given = config.overrides.get("connect/endpoints")  # a config file's (TLS)
    known = bound(config.listen) or list(config.connect) or list(given or [])
    join = f"MOVER_TEAM={team.name}"
    if known:
        join += f" MOVER_CONNECT={','.join(known)}"
    if config.mode == "client":
        join += " MOVER_MODE=client"
    if path := os.environ.get("MOVER_ZENOH_CONFIG"):
        join += f" MOVER_ZENOH_CONFIG=<its own certificate's config> (this process: {path})"
    key_file = os.environ.get("MOVER_TEAM_KEY_FILE")
    key = "the team's key (MOVER_TEAM_KEY or MOVER_TEAM_KEY_FILE, as this process has it)"
    if key_file and not os.environ.get("MOVER_TEAM_KEY"):
        key = f"the team's key (MOVER_TEAM_KEY_FILE={key_file})"
    return (
        f"READY {name}: serving {source} in team {team.name!r}; robots join with {join} and {key}"
    )


def serve(node: Node, door: LockstepDoor[Any], *, frames: bool = True) -> None:
    """Export ``door``'s calls on ``node`` and drop the robots whose process left.

    From now on liveness decides drops (``door.drop_silent`` is turned off: a silent robot
    that is still a member is waited for). With ``frames`` (and robots acting together), ticks
    are also taken and answered as frames (see ``sim_hw._frames``): the join's answer says so.
    """
    door.drop_silent = False
    offered = frames and door.turns == "together"
    if offered:
        _TickFrames(node, door)

    async def join(robot: str, spec: dict[str, Any]) -> dict[str, Any]:
        joined = await door.join(robot, spec or None)
        return {**joined, "frames": offered, "lead": door.control_delay}

    async def step(robot: str, tick: int, command: dict[str, Any]) -> dict[str, Any]:
        readings: dict[str, Any] = await door.step(robot, tick, command)
        return readings

    async def idle(robot: str, command: dict[str, Any], at: int | None = None) -> dict[str, Any]:
        door.idle(robot, command, at)
        readings: dict[str, Any] = await door.settled(robot)  # its last commands are in
        return readings

    def wake(robot: str) -> dict[str, Any]:
        readings: dict[str, Any] = door.wake(robot)
        return readings

    async def leave(robot: str) -> None:
        await door.leave(robot)

    def status() -> dict[str, Any]:
        return door.status()

    for fn in (join, step, idle, wake, leave, status):
        node.export(fn, name=fn.__name__)
    node.membership.on_gone(lambda name: door.drop(name, "left the team"))
    from sim_hw.view import export_scene  # what a viewer asks: view.scene (and view.frame)

    export_scene(node, door)


class _TickFrames:
    """The world's end of the tick frames: commands in, one frame of readings out per tick."""

    def __init__(self, node: Node, door: LockstepDoor[Any]) -> None:
        self.node, self.door = node, door
        commands, self.topic = topics(node.name)
        self.pending: dict[str, int] = {}  # robot -> the tick it waits on by frame
        self.refused = 0
        self.sub = node.subscribe(commands, maxlen=COMMAND_QUEUE)
        door.on_tick.append(self.flush)
        door.keep(asyncio.get_running_loop().create_task(self.run()))

    async def run(self) -> None:
        async for msg in self.sub:
            self.take(msg.sender, msg.data)

    def take(self, sender: str, data: Any) -> None:
        """One robot's command for a tick; only its sender may hand it in."""
        frame = read_command(sender, data)
        if frame is None:
            self.refused += 1
            log.debug("a malformed command frame from %r", sender)
            return
        robot, tick, command = frame
        self.pending[robot] = tick
        try:
            done = self.door.hand_in(robot, tick, command)
        except RobotDropped:  # the robot's fallback call will be told
            self.pending.pop(robot, None)
            return
        if done is not None and robot in self.pending:  # a retry for a tick already done
            del self.pending[robot]
            if not self.door.control_delay:  # (else the tick's frame had every robot's entry)
                self.send({robot: done})

    def flush(self, commands: Mapping[str, Command]) -> None:
        """The tick is done: one frame with the readings of every robot that asked by frame,
        and of every idle robot (so that their readings stay current); with a control delay,
        of every robot."""
        door = self.door
        idle = door.idle_robots
        if not self.pending and not idle and not door.control_delay:
            return
        st = door.stepper
        robots = st.robots()
        if door.control_delay:  # robots run behind the world: each finds its entry queued
            entries = {r: st.readings(r) for r in sorted(robots)}
        else:
            entries = {r: st.readings(r) for r in sorted({*self.pending, *idle}) if r in robots}
        self.pending.clear()
        if entries:
            self.send(entries)

    def send(self, entries: dict[str, Any]) -> None:
        frame = readings_frame(self.door.stepper.tick, entries)
        try:
            self.node.broadcast_nowait(self.topic, frame, reliable=True, express=True)
        except MoverError as exc:  # too large, or the node closing: robots will ask by call
            log.warning("tick frame not sent: %s", exc)


class Served(Protocol):
    """A world with its lock-step door (``WorldServer``, ``GridServer``)."""

    @property
    def door(self) -> LockstepDoor[Any]:
        """The door robots join and step through."""


W = TypeVar("W", bound=Served)


async def run_world_process(
    server: W,
    export: Callable[[Node, W], None],
    *,
    name: str,
    team: TeamCredentials,
    config: NodeConfig,
    until_tick: int | None = None,
    quit_when_empty: bool = False,
    ready: Callable[[], None] | None = None,
) -> None:
    """Open a node named ``name``, ``export(node, server)``, and run until the world reaches
    tick ``until_tick``, until every robot has left (``quit_when_empty``), or until cancelled;
    then close the server's door."""
    door = server.door
    async with Node(name, team=team, kind="world", config=config, unique=True) as node:
        export(node, server)
        log.info("world serving as %r", name)
        if ready is not None:
            ready()
        try:
            seen = False
            while until_tick is None or door.stepper.tick < until_tick:
                await asyncio.sleep(0.05)
                robots = bool(door.stepper.robots())
                seen = seen or robots
                if quit_when_empty and seen and not robots:
                    break
        finally:
            await door.aclose()
