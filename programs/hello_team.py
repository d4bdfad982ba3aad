"""hello_team: the smallest team program — radio by range, calls between robots, a collective.

Every robot says hello on a range-limited radio; each one reports whom it heard (distance and
bearing in its own frame), asks the nearest of them where it thinks it is (a remote call), and
all robots end together with everyone's findings.

A robot listens ``listen`` seconds after saying hello. The team starts saying it together, but
"together" is as close as the link allows: on one machine half a second is plenty; on a link of
50 ms each way that loses a packet now and then (each loss costs TCP 200 ms, then 400 ms, ...)
a hello can come later than that, and is then not heard. Give such a link a few seconds
(``mover run hello_team --args '{"listen": 2}'``).
"""

from __future__ import annotations

import asyncio
from typing import Any

from mover import RunTeam
from robots import Robot

MAX_LISTEN = 60.0


async def hello_team(
    robot: Robot, team: RunTeam, range: float = 3.0, listen: float = 0.5
) -> dict[str, Any]:
    """Say hello within ``range`` metres, listen ``listen`` seconds, call the nearest robot
    heard, share the findings."""
    assert robot.node is not None
    if not 0 <= listen <= MAX_LISTEN:
        raise ValueError(f"listen is {listen} s; from 0 to {MAX_LISTEN} s")
    hellos = robot.node.subscribe("hello")
    await team.distributed_and(lambda: asyncio.sleep(0.3))  # everyone is listening now
    await robot.node.broadcast("hello", robot.id, range=range, reliable=True)
    await asyncio.sleep(listen)
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
