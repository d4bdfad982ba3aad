"""Foraging behaviours on a grid floor (Simonin et al., "Collective construction of numerical
potential fields for the foraging problem", INRIA RR-6171, 2007).

Each behaviour is a plain object with ``step(perception) -> Action`` that owns its state and takes
its randomness from an injected ``numpy.random.Generator``; it reads and writes only the cell it
stands on and perceives the 4 neighbours — no map, no global position:

* :class:`MarkingAgent` — EXPLORATION & APF CONSTRUCTION (Algorithm 2);
* :class:`ForagingMarkingAgent` — SEARCH & RETURN TO BASE (Algorithm 3);
* :class:`CMarkingAgent` — colour-marking agents with trails (Algorithm 4);
* :class:`AntAgent` — the pheromone ant-model baseline (section 5.5).
"""

from robots.foraging._ants import AntAgent, compass_move
from robots.foraging._cmarking import TRAIL_COLOURS, CMarkingAgent, Task, ending
from robots.foraging._marking import (
    ForagingMarkingAgent,
    MarkingAgent,
    descend,
    explore,
    update_value,
)
from robots.foraging._types import (
    EAST,
    NO_COLOUR,
    NORTH,
    OFFSETS,
    SOUTH,
    TRAIL,
    UNMARKED,
    WEST,
    Action,
    AntNeighbour,
    AntPerception,
    Neighbour,
    Perception,
    opposite,
)

__all__ = [
    "EAST",
    "NORTH",
    "NO_COLOUR",
    "OFFSETS",
    "SOUTH",
    "TRAIL",
    "TRAIL_COLOURS",
    "UNMARKED",
    "WEST",
    "Action",
    "AntAgent",
    "AntNeighbour",
    "AntPerception",
    "CMarkingAgent",
    "ForagingMarkingAgent",
    "MarkingAgent",
    "Neighbour",
    "Perception",
    "Task",
    "compass_move",
    "descend",
    "ending",
    "explore",
    "opposite",
    "update_value",
]
