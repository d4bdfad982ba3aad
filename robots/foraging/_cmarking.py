"""Colour-marking (c-marking) agents: Simonin et al., Algorithm 4 and section 4.4.

On top of the marking agent's wavefront, an agent that loads at a resource which is not yet
exhausted colours its way back to the base (RETURN & COLOUR TRAIL), so that others can climb the
trail from the base (SEARCH & CLIMB TRAIL). The agent that exhausts a resource descends the
coloured trail and restores the default colour (RETURN & REMOVE TRAIL). Every step also performs
UPDATE-VALUE, so the potential field keeps converging whatever the agent is doing ("coloured
trails do not change the potential field construction").

Choices the paper leaves open, taken here:

* the resource cell itself is coloured when a trail is created (and cleared when it is removed),
  so that LOADING's test "is the cell coloured (part of a trail)?" means "a trail already leads
  here"; the base is never coloured;
* RETURN & REMOVE TRAIL follows the trail-coloured new neighbour of least value; when no such
  neighbour is left (the trail ends, or was already erased) it finishes as a plain descent;
* an agent that arrives in a resource cell already emptied by another simply goes on searching.
"""

from __future__ import annotations

import enum

import numpy as np

from robots.foraging._dice import Dice
from robots.foraging._marking import descend, explore, resource_neighbour, update_value
from robots.foraging._types import NO_COLOUR, TRAIL, Action, Neighbour, Perception, opposite


class Task(enum.IntEnum):
    """The tasks of Algorithm 4 an agent can be in."""

    SEARCH = 0  # SEARCH & CLIMB TRAIL
    RETURN = 1  # RETURN TO BASE (descent; the resource is already on a trail)
    COLOUR = 2  # RETURN & COLOUR TRAIL
    REMOVE = 3  # RETURN & REMOVE TRAIL


class CMarkingAgent:
    """A colour-marking foraging agent (Simonin et al., Algorithm 4)."""

    def __init__(self, rng: np.random.Generator, q_max: int = 100) -> None:
        self._dice = Dice(rng)
        self.q_max = q_max
        self.task = Task.SEARCH
        self.load = 0
        #: Direction of the previous cell, as seen from the current one (None at start).
        self.came_from: int | None = None

    def step(self, p: Perception) -> Action:
        """One iteration: UPDATE-VALUE, LOADING or unloading where due, then move."""
        value = update_value(p)
        task = self.task
        load = 0
        unload = False
        colour: int | None = None
        if task == Task.SEARCH and p.resource > 0:
            # LOADING: pick up q_max; the world gives at most what is left.
            load = min(self.q_max, p.resource)
            self.load = load
            if p.resource - load > 0:
                task = Task.RETURN if p.colour == TRAIL else Task.COLOUR
            else:
                task = Task.REMOVE
        elif task != Task.SEARCH and p.at_base:
            unload = True  # at the base: unload and execute SEARCH & CLIMB
            self.load = 0
            task = Task.SEARCH
        dice = self._dice
        if task == Task.SEARCH:
            move = self._search(p.neighbours, dice)
        elif task == Task.COLOUR:
            colour = TRAIL  # RETURN & COLOUR TRAIL: colour the cells of the descent
            move = descend(p.neighbours, dice)
        elif task == Task.REMOVE:
            if p.colour == TRAIL:
                colour = NO_COLOUR
            move = self._follow_trail_down(p.neighbours, value, dice)
            if move is None:
                task = Task.RETURN
                move = descend(p.neighbours, dice)
        else:
            move = descend(p.neighbours, dice)
        self.task = task
        self.came_from = None if move is None else opposite(move)
        return Action(move, value, colour, load, unload)

    def _search(self, neighbours: tuple[Neighbour, ...], dice: Dice) -> int | None:
        """SEARCH & CLIMB TRAIL: resource, else climb the highest coloured new neighbour, else
        EXPLORATION (Algorithm 2)."""
        move = resource_neighbour(neighbours, dice)
        if move is not None:
            return move
        back = self.came_from
        best = -1
        ties: list[Neighbour] = []
        for n in neighbours:
            if n.colour != TRAIL or n.direction == back:
                continue
            if n.value > best:
                best = n.value
                ties = [n]
            elif n.value == best:
                ties.append(n)
        if ties:
            return dice.choice(ties).direction
        return explore(neighbours, dice)

    def _follow_trail_down(
        self, neighbours: tuple[Neighbour, ...], here: int, dice: Dice
    ) -> int | None:
        """RETURN & REMOVE TRAIL: the trail-coloured new neighbour of least value below ``here``."""
        back = self.came_from
        best = -1
        ties: list[Neighbour] = []
        for n in neighbours:
            if n.colour != TRAIL or n.direction == back or n.value < 0 or n.value >= here:
                continue
            if best < 0 or n.value < best:
                best = n.value
                ties = [n]
            elif n.value == best:
                ties.append(n)
        return dice.choice(ties).direction if ties else None
