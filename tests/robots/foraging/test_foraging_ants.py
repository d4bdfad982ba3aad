"""The ant-model baseline (section 5.5): compass homing, pheromone, and the cavity trap."""

from __future__ import annotations

from typing import Literal, overload

import numpy as np

from robots.foraging import AntAgent, AntNeighbour, AntPerception, CMarkingAgent
from sim_hw.grid import GridWorld, PheromoneField, parse_text

# A cavity whose mouth faces away from the base B; the resource R lies against its back wall.
CAVITY = """\
...............
...............
...............
...............
.........#####.
.........#.....
.........#.....
..B......#R....
.........#.....
.........#.....
.........#####.
...............
...............
...............
...............
"""


def ant(seed: int = 0) -> AntAgent:
    return AntAgent(np.random.default_rng(seed))


def test_returning_ant_follows_compass_and_drops_pheromone() -> None:
    a = ant()
    nbrs = tuple(AntNeighbour(d, 0.0, 0, False) for d in range(4))
    act = a.step(AntPerception(0.0, 500, False, nbrs, (0.0, -1.0)))  # base due west
    assert act.load == 100 and act.move == 3 and act.drop > 0


def test_searching_ant_climbs_pheromone_away_from_home() -> None:
    a = ant()
    nbrs = (
        AntNeighbour(0, 500.0, 0, False),  # toward home: not climbed
        AntNeighbour(1, 100.0, 0, False),
        AntNeighbour(2, 80.0, 0, False),
    )
    assert a.step(AntPerception(90.0, 0, False, nbrs, (-1.0, 0.0))).move == 1


@overload
def world_with(kind: Literal["ants"], n: int, seed: int) -> tuple[GridWorld, list[AntAgent]]: ...
@overload
def world_with(
    kind: Literal["cmarking"], n: int, seed: int
) -> tuple[GridWorld, list[CMarkingAgent]]: ...
def world_with(
    kind: str, n: int, seed: int
) -> tuple[GridWorld, list[AntAgent] | list[CMarkingAgent]]:
    lay = parse_text(CAVITY)
    assert lay.base is not None
    res = {(7, 10): 300}
    rngs = np.random.default_rng(seed).spawn(n)
    if kind == "ants":
        field = PheromoneField(~lay.grid.obstacles)
        return GridWorld(lay.grid, lay.base, res, n, pheromone=field), [AntAgent(r) for r in rngs]
    return GridWorld(lay.grid, lay.base, res, n), [CMarkingAgent(r) for r in rngs]


def test_ants_get_stuck_in_a_cavity_where_c_marking_agents_do_not() -> None:
    ants, ant_agents = world_with("ants", 5, 1)
    for _ in range(3000):
        ants.step(ant_agents, True)
    stuck = [i for i, a in enumerate(ant_agents) if a.returning]
    assert ants.delivered == 0 and stuck  # loaded, but never home
    assert all(5 <= ants.agent_cell(i)[0] <= 9 and ants.agent_cell(i)[1] >= 10 for i in stuck)

    cm, cm_agents = world_with("cmarking", 5, 1)
    while not cm.all_delivered and cm.iteration < 3000:
        cm.step(cm_agents)
    assert cm.all_delivered and cm.delivered == 300
