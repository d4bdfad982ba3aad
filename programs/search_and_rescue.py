"""Search and rescue, MOVER's Figure 3 (Jennings et al., sections 4.2-4.3) in Python.

Every member of the team runs this program. ``distributed_or``: all search, the first to find
an object it recognises wins and the others stop (Figure 2, 3-5). ``distributed_and``: every
robot goes to its place at the winner's object, and nobody goes on until all have arrived
(Figure 2, 6-8). Then the finder pushes and the others steer the object along ``path``, given
as offsets from where it was found (section 4.1 "Manipulation"; Figure 2, 9).
"""

from __future__ import annotations

import random
from typing import Any

from mover import RunTeam
from robots import Robot
from robots.library import (
    Found,
    Path,
    goto_object,
    pusher,
    recognition,
    search,
    stations,
    steerer,
)


async def search_and_rescue(
    robot: Robot,
    team: RunTeam,
    path: list[list[float]] | None = None,
    width: float = 1.2,
    recognise: str = "box",
    seed: int | None = None,
) -> dict[str, Any]:
    """Find an object, gather at it, move it along ``path`` (default: 3 m along +x).

    ``width`` is the object's width across the path (where the robots stand along its rear
    face); ``recognise`` is ``"push"`` for the paper's push test or a camera kind. The random
    walk draws from ``team.rng("search")`` (the run's seed), or, given ``seed``, from a
    generator of ``seed`` and this robot's name.
    Returns the winner, the object's estimated start and how far this robot saw it move.
    """
    rng = team.rng("search") if seed is None else random.Random(f"{seed}/{team.me}")
    await team.report("searching")
    won = await team.distributed_or(lambda: search(robot, recognition(recognise), rng=rng))
    found = Found.load(won.result)
    plan = Path.relative(found.location, path or [[3.0, 0.0]])
    role, lateral = stations(won.winner, team.members, width)[team.me]
    await team.report("found", winner=won.winner, object=found.object_id)
    await team.report("gathering", role=role)
    await team.distributed_and(
        lambda: goto_object(
            robot, found.location, plan.heading(), lateral, object_id=found.object_id
        )
    )
    await team.report("pushing", role=role)
    moved = await (
        pusher(robot, plan, object_id=found.object_id)
        if role == "pusher"
        else steerer(robot, plan, lateral, object_id=found.object_id)
    )
    return {
        "winner": won.winner,
        "object": found.object_id,
        "role": role,
        "location": list(found.location),
        "moved": moved["moved"],
    }
