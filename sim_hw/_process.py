"""The world process: a :class:`WorldServer` exported over a mover node.

Robots call ``join(robot, spec)``, ``step(robot, tick, command)`` (one call per tick; in
lock-step the reply comes once every robot's command for the tick is in and the world has
stepped) and ``leave(robot)``. Snapshots go out on the team-wide topic ``world/state``.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sim_hw.continuous._server import WorldServer

log = logging.getLogger("sim_hw.process")

STATE_TOPIC = "world/state"


def serve_world(node: Any, server: WorldServer, *, state_topic: str = STATE_TOPIC) -> None:
    """Export ``server``'s three calls on ``node`` and send its snapshots to ``state_topic``."""

    async def join(robot: str, spec: dict[str, Any]) -> dict[str, Any]:
        return await server.join(robot, spec or None)

    async def step(robot: str, tick: int, command: dict[str, Any]) -> dict[str, Any]:
        return await server.step(robot, tick, command)

    async def leave(robot: str) -> None:
        await server.leave(robot)

    node.export(join, name="join")
    node.export(step, name="step")
    node.export(leave, name="leave")
    # a robot process that dies is seen leaving the team within milliseconds (its liveliness
    # token goes); the lock-step timeout still catches one that hangs
    # on_gone: a member whose link flaps (leaves and joins again within a second) keeps its body
    node.team.on_gone(lambda name: server.drop(name, "left the team"))
    if server.on_snapshot is None and server.snapshot_every:
        send = getattr(node, "broadcast_nowait", None) or node.broadcast
        server.on_snapshot = lambda snap: send(state_topic, snap)


async def run_world_process(
    server: WorldServer,
    *,
    name: str = "world",
    until: float | None = None,
    quit_when_empty: bool = False,
    team: Any = None,
    config: Any = None,
) -> None:
    """Open a node named ``name`` (``team`` and ``config`` default to the environment's),
    serve the world, and run until simulated time ``until``, until every robot has left
    (``quit_when_empty``), or until cancelled."""
    from mover import Node, NodeConfig, Team

    team = team or Team.from_env()
    config = config or NodeConfig.from_env()
    async with Node(name, team=team, kind="world", config=config) as node:
        serve_world(node, server)
        log.info("world %r serving as %r", server.world.spec.name, name)
        try:
            seen = False
            while until is None or server.world.time < until:
                await asyncio.sleep(0.05)
                seen = seen or bool(server.world.robots)
                if quit_when_empty and seen and not server.world.robots:
                    break
        finally:
            await server.aclose()
