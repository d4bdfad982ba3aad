"""Pheromone dynamics for the ant-model baseline (Simonin et al., section 5.5).

Each iteration every cell passes a fraction ``diffusion`` of its pheromone, in equal quarters, to
its 4 neighbours (a quarter aimed at an obstacle or the border stays where it is, so diffusion
conserves the total), then every cell loses a fraction ``evaporation``. The paper's tuned rates are
95 % diffusion and 0.5 % evaporation.
"""

from __future__ import annotations

import numpy as np


class PheromoneField:
    """A float layer over a grid's free cells with diffusion and evaporation, vectorised."""

    def __init__(self, free: np.ndarray, diffusion: float = 0.95, evaporation: float = 0.005):
        if not (0.0 <= diffusion <= 1.0 and 0.0 <= evaporation <= 1.0):
            raise ValueError("diffusion and evaporation are fractions in [0, 1]")
        self.free = np.asarray(free, dtype=bool)
        self.diffusion = diffusion
        self.evaporation = evaporation
        h, w = self.free.shape
        self.values = np.zeros(h * w)  # flat, indexed like the world's cells
        f = self.free.astype(float)
        # Free neighbours toward north, east, south, west (0 outside and on obstacles).
        self._to = np.zeros((4, h, w))
        self._to[0, 1:, :] = f[:-1, :]
        self._to[1, :, :-1] = f[:, 1:]
        self._to[2, :-1, :] = f[1:, :]
        self._to[3, :, 1:] = f[:, :-1]
        self._to *= f  # only free cells hold and pass pheromone
        self._kept = (4.0 - self._to.sum(axis=0)) * f

    def update(self) -> None:
        """One iteration of diffusion then evaporation."""
        h, w = self.free.shape
        v = self.values.reshape(h, w)
        q = v * (self.diffusion / 4.0)
        out = v * (1.0 - self.diffusion) + q * self._kept
        to = self._to
        out[:-1, :] += (q * to[0])[1:, :]  # passed north
        out[:, 1:] += (q * to[1])[:, :-1]  # passed east
        out[1:, :] += (q * to[2])[:-1, :]  # passed south
        out[:, :-1] += (q * to[3])[:, 1:]  # passed west
        out *= 1.0 - self.evaporation
        self.values = out.ravel()

    def total(self) -> float:
        """Total pheromone on the floor."""
        return float(self.values.sum())
