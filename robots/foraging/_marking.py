"""Marking agents: the collective wavefront of Simonin et al., Algorithms 2 and 3.

An agent reads and writes only the integer value of the cell it stands on and perceives its 4
neighbours. One ``step`` is one iteration of section 5.1: UPDATE-VALUE on the current cell (the
update the algorithm performs right after each move), then the choice of the next move. Doing the
update at the start of the next step rather than at the end of the move is the same sequence of
writes, and lets the behaviour see the neighbours of the cell it writes.
"""

from __future__ import annotations

import numpy as np

from robots.foraging._dice import Dice
from robots.foraging._types import UNMARKED, Action, Neighbour, Perception


def update_value(p: Perception) -> int:
    """UPDATE-VALUE (Algorithm 2): ``min(val, 1 + min(4-neighbour values))``.

    Unmarked cells count as infinity (Algorithm 1's ``M``); a cell with no marked neighbour keeps
    its value (it stays unmarked if it was).
    """
    best = -1
    for n in p.neighbours:
        v = n.value
        if v >= 0 and (best < 0 or v < best):
            best = v
    if best < 0:
        return p.value
    cand = best + 1
    val = p.value
    return cand if val < 0 or cand < val else val


def explore(neighbours: tuple[Neighbour, ...], dice: Dice) -> int | None:
    """EXPLORATION (Algorithm 2): a random unmarked neighbour if any, else any free neighbour."""
    unmarked = [n for n in neighbours if n.value == UNMARKED]
    if unmarked:
        return dice.choice(unmarked).direction
    if neighbours:
        return dice.choice(neighbours).direction
    return None


def descend(neighbours: tuple[Neighbour, ...], dice: Dice) -> int | None:
    """Descent (section 2): move to the marked neighbour of least value, ties broken at random."""
    best = -1
    ties: list[Neighbour] = []
    for n in neighbours:
        v = n.value
        if v < 0:
            continue
        if best < 0 or v < best:
            best = v
            ties = [n]
        elif v == best:
            ties.append(n)
    return dice.choice(ties).direction if ties else None


def resource_neighbour(neighbours: tuple[Neighbour, ...], dice: Dice) -> int | None:
    """A random neighbour holding resources, or None (Algorithms 3 and 4, first line of SEARCH)."""
    found = [n for n in neighbours if n.resource > 0]
    return dice.choice(found).direction if found else None


class MarkingAgent:
    """EXPLORATION & APF CONSTRUCTION (Simonin et al., Algorithm 2).

    Builds the wavefront (BFS distance) from the goal cell, which holds 0 before agents start.
    """

    def __init__(self, rng: np.random.Generator) -> None:
        self._dice = Dice(rng)

    def step(self, p: Perception) -> Action:
        """Update the current cell, then move, preferring unmarked neighbours."""
        return Action(explore(p.neighbours, self._dice), update_value(p))


class ForagingMarkingAgent:
    """SEARCH & RETURN TO BASE (Simonin et al., Algorithm 3): marking agents that forage.

    SEARCH explores as Algorithm 2 until a resource is detected in a neighbouring cell; the agent
    moves into it, loads ``q_max`` units and returns to the base by descending the field,
    still updating values on the way.
    """

    def __init__(self, rng: np.random.Generator, q_max: int = 100) -> None:
        self._dice = Dice(rng)
        self.q_max = q_max
        self.returning = False

    def step(self, p: Perception) -> Action:
        """One iteration: update, load or unload where due, then search or descend."""
        value = update_value(p)
        load = 0
        unload = False
        if not self.returning and p.resource > 0:
            load = self.q_max  # loading happens on arrival in the resource cell
            self.returning = True
        elif self.returning and p.at_base:
            unload = True  # RETURN TO BASE: unload and execute SEARCH
            self.returning = False
        dice = self._dice
        if self.returning:
            move = descend(p.neighbours, dice)
        else:
            move = resource_neighbour(p.neighbours, dice)
            if move is None:
                move = explore(p.neighbours, dice)
        return Action(move, value, None, load, unload)
