"""hello_team: the smallest team program — radio by range, calls between robots, a collective.

Every robot says hello on a range-limited radio; each one reports whom it heard (distance and
bearing in its own frame), asks the nearest of them where it thinks it is (a remote call), and
all robots end together with everyone's findings.
"""

from __future__ import annotations

import asyncio
from typing import Any

from mover import RunTeam
from robots import Robot


async def hello_team(robot: Robot, team: RunTeam, range: float = 3.0) -> dict[str, Any]:
    """Say hello within ``range`` metres, call the nearest robot heard, share the findings."""
    assert robot.node is not None
    hellos = robot.node.subscribe("hello")
    await team.distributed_and(lambda: asyncio.sleep(0.3))  # everyone is listening now
    await robot.node.broadcast("hello", robot.id, range=range, reliable=True)
    await asyncio.sleep(0.5)
    heard = {
        m.sender: [round(m.distance or 0.0, 2), round(m.bearing or 0.0, 2)] for m in hellos.drain()
    }
    hellos.close()
    await team.report("heard", who=sorted(heard))
    nearest = min(heard, key=lambda n: heard[n][0], default=None)
    pose = await robot.node.call(nearest, "robot.pose", timeout=5) if nearest else None
    mine = {"heard": heard, "nearest": nearest, "nearest_pose": pose}
    everyone = await team.distributed_and(lambda: _value(mine))
    return {"me": mine, "team_size": len(everyone)}


async def _value(value: Any) -> Any:
    return value
