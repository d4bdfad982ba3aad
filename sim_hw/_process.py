"""The world process of both worlds: a lock-step door exported over a mover node.

Robots call ``join(robot, spec)``, ``step(robot, tick, command)`` (in lock-step the reply comes
once every robot's command for the tick is in and the world has stepped) and ``leave(robot)``.
A robot whose process leaves the team is dropped (``team.on_gone``: only once it has stayed
gone for a second, so a flapping link keeps its body); the door's own timeout still catches
one that hangs. :func:`run_world_process` is the one main of ``mover world`` and ``mover
gridworld``.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

from sim_hw._lockstep import LockstepDoor

log = logging.getLogger("sim_hw.process")

STATE_TOPIC = "world/state"
"""The team-wide topic on which a world process streams its snapshots."""


def serve(node: Any, door: LockstepDoor[Any]) -> None:
    """Export ``door``'s three calls on ``node`` and drop the robots whose process left."""

    async def join(robot: str, spec: dict[str, Any]) -> dict[str, Any]:
        return await door.join(robot, spec or None)

    async def step(robot: str, tick: int, command: dict[str, Any]) -> dict[str, Any]:
        return await door.step(robot, tick, command)

    async def leave(robot: str) -> None:
        await door.leave(robot)

    for fn in (join, step, leave):
        node.export(fn, name=fn.__name__)
    node.team.on_gone(lambda name: door.drop(name, "left the team"))


async def run_world_process(
    door: LockstepDoor[Any],
    export: Callable[[Any, Any], None],
    *,
    name: str,
    team: Any,
    config: Any,
    until_tick: int | None = None,
    quit_when_empty: bool = False,
    ready: Callable[[], None] | None = None,
) -> None:
    """Open a node named ``name``, ``export(node, door)``, and run until the world reaches
    tick ``until_tick``, until every robot has left (``quit_when_empty``), or until cancelled."""
    from mover import Node

    async with Node(name, team=team, kind="world", config=config) as node:
        export(node, door)
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
