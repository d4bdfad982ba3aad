"""The ant-model baseline of Simonin et al., section 5.5 (after Resnick [24] and Parunak [23]).

An ant that finds a resource loads ``q_max`` units and walks home with a compass (it "knows the
direction of the base from its current cell"), dropping pheromone on every cell of the way back.
A searching ant moves into a neighbouring resource if it detects one, else climbs the pheromone
gradient away from the base, else walks at random. Diffusion and evaporation of the pheromone are
the environment's job (``sim_hw.grid.PheromoneField``, with the paper's tuned 95 % diffusion and
0.5 % evaporation). With only a compass to go home, an ant can be caught in a cavity whose mouth
faces away from the base (Figure 11.a): every move toward the base is blocked and a step out of
the cavity is undone by the next compass step.

The deposit and detection threshold are not given in the paper. The deposit follows Resnick's
StarLogo ants (60 units per cell). With 95 % diffusion the pheromone soon covers the whole floor
thinly, and Resnick's threshold (0.05) then sends searching ants "away from home" into the walls
and corners, where they pile up; a short sweep on Setup 3, 25×25 (thresholds 5, 20, 60, 120, 250
and no climbing at all) was fastest at 60, one fresh drop's worth, the default here.
"""

from __future__ import annotations

import numpy as np

from robots.foraging._dice import Dice
from robots.foraging._types import OFFSETS, Action, AntNeighbour, AntPerception, opposite


def compass_move(p: AntPerception, dice: Dice) -> int | None:
    """The free neighbour most aligned with the base direction, or a random one if none is.

    A random step when every move toward the base is blocked is the ant's only way out of an
    obstacle; in a cavity facing away from the base it is undone at the next step.
    """
    hr, hc = p.home
    best = 0.0
    ties: list[AntNeighbour] = []
    for n in p.neighbours:
        dr, dc = OFFSETS[n.direction]
        dot = dr * hr + dc * hc
        if dot > best + 1e-12:
            best = dot
            ties = [n]
        elif ties and abs(dot - best) <= 1e-12:
            ties.append(n)
    if ties:
        return dice.choice(ties).direction
    return dice.choice(p.neighbours).direction if p.neighbours else None


class AntAgent:
    """A pheromone-dropping foraging ant with a compass toward its nest (section 5.5, Fig. 10)."""

    def __init__(
        self,
        rng: np.random.Generator,
        q_max: int = 100,
        deposit: float = 60.0,
        threshold: float = 60.0,
    ) -> None:
        self._dice = Dice(rng)
        self.q_max = q_max
        self.deposit = deposit
        self.threshold = threshold
        self.returning = False
        self.came_from: int | None = None

    def step(self, p: AntPerception) -> Action:
        """One iteration: load or unload where due, then go home (dropping pheromone) or search."""
        load = 0
        unload = False
        if not self.returning and p.resource > 0:
            load = self.q_max
            self.returning = True
        elif self.returning and p.at_base:
            unload = True
            self.returning = False
        dice = self._dice
        drop = 0.0
        if self.returning:
            drop = self.deposit  # pheromone is laid on the way back only
            move = compass_move(p, dice)
        else:
            move = self._search(p, dice)
        self.came_from = None if move is None else opposite(move)
        return Action(move, None, None, load, unload, drop)

    def _search(self, p: AntPerception, dice: Dice) -> int | None:
        """SEARCH & CLIMB PHEROMONE: resource, else the strongest scent away from home, else
        a random step."""
        found = [n for n in p.neighbours if n.resource > 0]
        if found:
            return dice.choice(found).direction
        hr, hc = p.home
        best = self.threshold
        ties: list[AntNeighbour] = []
        for n in p.neighbours:
            if n.direction == self.came_from:
                continue
            dr, dc = OFFSETS[n.direction]
            if dr * hr + dc * hc > 1e-12:  # climbing leads away from the nest
                continue
            if n.pheromone > best:
                best = n.pheromone
                ties = [n]
            elif ties and n.pheromone == best:
                ties.append(n)
        if ties:
            return dice.choice(ties).direction
        return dice.choice(p.neighbours).direction if p.neighbours else None
