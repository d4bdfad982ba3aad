"""What a foraging agent senses and what it does: the interface between behaviours and worlds.

Simonin et al. (section 3.1) give an agent a cell to stand on and the 4 neighbouring cells to
perceive: it reads and writes an integer value (and, for c-marking agents, a colour) on its own
cell, sees which neighbours are obstacles, reads their values and detects resources in them. It
has no map and no global position. The ant model (section 5.5) senses pheromone instead of values
and has a compass toward the base. These types are plain tuples: cheap to build in a tight loop and
msgpack-able as they are.
"""

from __future__ import annotations

from typing import NamedTuple

from robots.grid_hal import OFFSETS as ALL_OFFSETS

#: Value of a floor cell that no agent has marked yet (the paper's "cell without a value").
UNMARKED = -1
#: The default colour of a floor cell (no trail).
NO_COLOUR = 0
#: The trail colour written by c-marking agents (Simonin et al., section 4.4).
TRAIL = 1

#: Move directions, in the order a world lists neighbours: north, east, south, west.
NORTH, EAST, SOUTH, WEST = 0, 1, 2, 3
#: (row, column) offset of each direction (the first four of the grid HAL's).
OFFSETS = ALL_OFFSETS[:4]


def opposite(direction: int) -> int:
    """The direction pointing back to where a move in ``direction`` came from."""
    return (direction + 2) % 4


class Neighbour(NamedTuple):
    """One free (non-obstacle) neighbouring cell as a marking agent perceives it."""

    direction: int
    value: int
    colour: int
    resource: int
    base: bool


class Perception(NamedTuple):
    """What a marking agent senses where it stands: its own cell and its free neighbours.

    Obstacle neighbours are simply absent from ``neighbours``.
    """

    value: int
    colour: int
    resource: int
    at_base: bool
    neighbours: tuple[Neighbour, ...]


class AntNeighbour(NamedTuple):
    """One free neighbouring cell as an ant perceives it (pheromone instead of values)."""

    direction: int
    pheromone: float
    resource: int
    base: bool


class AntPerception(NamedTuple):
    """What an ant senses: pheromone here and around, resources, and a compass to the base.

    ``home`` is the unit vector (d_row, d_col) from the ant toward the base (section 5.5: each
    ant "knows the direction of the base from its current cell"); (0, 0) at the base.
    """

    pheromone: float
    resource: int
    at_base: bool
    neighbours: tuple[AntNeighbour, ...]
    home: tuple[float, float]


class Action(NamedTuple):
    """What an agent does in one iteration: write its cell, load/unload, then move.

    ``value``/``colour`` are written on the current cell (None: leave as is); ``load`` asks for
    that many resource units from the current cell (the world gives at most what is there);
    ``unload`` drops the load when at the base; ``drop`` adds pheromone to the current cell;
    ``move`` is a direction or None (stay).
    """

    move: int | None
    value: int | None = None
    colour: int | None = None
    load: int = 0
    unload: bool = False
    drop: float = 0.0
