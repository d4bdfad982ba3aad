"""Lévy-flight search with a potential field (Sutantyo et al.) as robot processes.

Every member runs one walk of :data:`robots.library.METHODS` — the same
:class:`robots.library.LevyWalker` the in-process runner steps — on its own HAL. With ``L+P``
each robot broadcasts its presence every tick within ρ0 and is repelled (eq. 9) by the
robots it hears, from the distance and bearing the broadcast gives; a robot that finds a
target marks it (its LED's message to the target) and tells the team, once, team-wide; marked
targets repel robots within the signature range (their cameras see the target's status). The
team agrees on a start tick first, so that every robot starts deciding at the same tick; the
search ends on each robot when it has heard of ``targets`` finds.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mover import RunTeam
from robots import Robot, library
from robots.library import LevyParams, Neighbour, walker

from ._start import common_start

HERE, FOUND = "levy/here", "levy/found"


async def levy_search(
    robot: Robot,
    team: RunTeam,
    method: str = "L+P",
    targets: int = 1,
    seed: int | None = None,
    alpha: float = 1.0,
    scale: float = 1.0,
    cap: float = 20.0,
    fixed: float = 1.0,
    speed: float = 0.6,
    sense_range: float = 1.0,
    signature_range: float = 3.0,
    rho0: float = 1.5,
    max_time: float = 6000.0,
) -> dict[str, Any]:
    """Search until the team has found ``targets`` targets (or ``max_time`` s have passed).

    Robot i of the members in name order walks with ``np.random.default_rng([seed, i])``, as
    ``experiments.levy.run_world`` seeds it (``seed`` defaults to the run's, ``team.seed``).
    Returns the targets this robot marked, every find it knows of (seconds after the common
    start) and the search time (the last find).
    """
    hw, node = robot.hw, team.node
    seed = team.seed if seed is None else seed
    rng = np.random.default_rng([seed, sorted(team.members).index(team.me)])
    cfg = LevyParams(
        speed=speed, sense_range=sense_range, signature_range=signature_range, rho0=rho0
    )
    walk = walker(method, rng, alpha=alpha, scale=scale, cap=cap, fixed=fixed, params=cfg)
    found: dict[str, float] = {}
    here, heard = node.subscribe(HERE), node.subscribe(FOUND)

    async def now() -> float:
        return hw.clock.now()

    start = await common_start(hw.clock, team)

    def neighbours() -> list[Neighbour]:
        if method != "L+P":
            return []
        node.broadcast_nowait(HERE, None, range=rho0)
        latest = {m.sender: m for m in here.drain() if m.distance is not None}
        return [(m.distance, m.bearing or 0.0) for m in latest.values() if m.distance]

    def record(target: str, t: float) -> None:  # the earliest report of a find counts
        found[target] = min(t, found.get(target, t))

    def marked(target: str, t: float) -> None:
        record(target, t - start)
        node.broadcast_nowait(FOUND, {"target": target, "t": t - start}, reliable=True)

    def over() -> bool:
        for m in heard.drain():
            record(str(m.data["target"]), float(m.data["t"]))
        return len(found) >= targets or hw.clock.now() - start > max_time

    mine = await library.levy_search(robot, walk, neighbours, over, marked)
    await team.distributed_and(now)  # everyone stops before anyone leaves the world
    here.close()
    heard.close()
    times = sorted(found.values())
    return {
        "marked": sorted(mine),
        "found": found,
        "time": times[-1] if len(times) >= targets else None,
        "start": start,
    }
