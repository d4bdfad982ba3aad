"""The pymunk world as the lock-step door drives it, and :class:`WorldServer`, a world and its door.

:class:`WorldStepper` adapts a :class:`World` to the door's stepper protocol
(``sim_hw._lockstep``): robots are in the world as soon as they join (``admits_early``) and
are re-created in id order when the expected ones are in, so that the run does not depend on
the order they came in; the door answers their joins then, with the readings after the
re-creation (the same whatever the order). A world with eye-bots is served by the two-layer
stepper of ``_skyworld`` (:func:`stepper_for`).
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Awaitable, Callable, Collection, Mapping
from dataclasses import asdict
from typing import Any

from mover import Node
from sim_hw._lockstep import Command, LockstepDoor, Readings
from sim_hw._process import STATE_TOPIC, serve

from ._contract import TICK
from ._spec import RobotSpec
from ._world import World
from ._worldfile import parse_robot

log = logging.getLogger("sim_hw.continuous")

Snapshot = dict[str, Any]


class WorldStepper:
    """A :class:`World` behind the door: one tick is ``STEPS_PER_TICK`` physics steps."""

    admits_early = True
    words = ("command", "tick")

    def __init__(self, world: World) -> None:
        self.world = world

    @property
    def tick(self) -> int:
        """Ticks done."""
        return self.world.tick

    def robots(self) -> Collection[str]:
        """Ids of the robots in the world."""
        return self.world.robots.keys()

    def prepare(self, robot: str, spec: Mapping[str, Any] | None) -> RobotSpec:
        """The world file's settings for ``robot``, overridden by ``spec`` (checked)."""
        base = self.world.spec.robots.get(robot, self.world.spec.robot)
        return parse_robot(dict(spec or {}), base, f"join({robot})")

    def admit(self, robot: str, prepared: RobotSpec) -> None:
        """Spawn ``robot``."""
        self.world.add_robot(robot, prepared)

    def start(self) -> None:
        """Re-create the robots in id order (they came in arrival order; nothing has moved)."""
        self.world.respawn_robots()

    def advance(self, commands: Mapping[str, Command]) -> None:
        """Set the commands and run one tick."""
        for robot, command in commands.items():
            self.world.set_command(robot, command)
        self.world.step()

    def sense(self) -> None:
        """Nothing to do: the world measures at every tick and at every spawn."""

    def readings(self, robot: str) -> Readings:
        """``robot``'s readings from the end of the last tick."""
        return self.world.readings(robot)

    def spec_of(self, robot: str) -> dict[str, Any]:
        """The settings ``robot`` was spawned with."""
        return asdict(self.world.robots[robot].parts.spec)

    def remove(self, robot: str) -> None:
        """Take ``robot`` out of the world."""
        self.world.remove_robot(robot)


def stepper_for(world: World) -> WorldStepper:
    """The door's stepper for ``world``: with eye-bots on its ceiling, the two-layer one."""
    if world.spec.eyebots:
        from ._skyworld import SkyStepper  # it builds on WorldStepper: imported when needed

        return SkyStepper(world)
    return WorldStepper(world)


class WorldServer:
    """A :class:`World` and the lock-step door (``door``) that runs it, in lock-step or in
    (scaled) real time, for the robots that join it.

    Robots join, step and leave through ``server.door`` (:class:`LockstepDoor`): the in-process
    HAL (:func:`sim_hw.in_process`) and a world process (:func:`serve_world`) take it from
    there; what runs after every tick (a recorder) is a hook on ``server.door.on_tick``.
    ``expect`` robots must join before a lock-step world starts (0: start at the first join);
    ``timeout`` wall seconds of silence in a tick drop a robot (in process; a world process
    only says so, see ``sim_hw._lockstep``). ``control_delay`` (lock-step): a command handed
    in for tick t applies at tick t + K (``sim_hw._delayed``).
    ``on_snapshot(snapshot)`` is called every ``snapshot_every`` ticks (0: never); it may be a
    coroutine function.
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
        control_delay: int = 0,
    ) -> None:
        if speed <= 0:
            raise ValueError("speed must be positive")
        self.world = world
        self.door: LockstepDoor[WorldStepper] = LockstepDoor(
            stepper_for(world),
            expect=expect,
            timeout=timeout,
            speed=None if lockstep else speed,
            period=TICK,
            control_delay=control_delay,
        )
        self.snapshot_every = snapshot_every
        self.on_snapshot = on_snapshot
        self.door.on_tick.append(self._publish)

    def _publish(self, commands: Mapping[str, Command]) -> None:
        every, send = self.snapshot_every, self.on_snapshot
        if not every or send is None or self.world.tick % every:
            return
        result = send(self.world.snapshot())
        if inspect.isawaitable(result):
            self.door.keep(asyncio.ensure_future(_quietly(result)), finish=True)


async def _quietly(awaitable: Awaitable[Any]) -> None:
    try:
        await awaitable
    except Exception as exc:  # a lost snapshot must not stop the world
        log.debug("snapshot hook failed: %s", exc)


def serve_world(node: Node, server: WorldServer, *, state_topic: str = STATE_TOPIC) -> None:
    """Export ``server``'s door on ``node`` and send its snapshots to ``state_topic``."""
    serve(node, server.door)
    if server.on_snapshot is None and server.snapshot_every:
        send = getattr(node, "broadcast_nowait", None) or node.broadcast
        server.on_snapshot = lambda snap: send(state_topic, snap)
