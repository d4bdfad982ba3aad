"""Fast uniform draws from an injected numpy Generator.

A scalar ``Generator.integers`` call costs about a microsecond, which dominates a behaviour's step
in a tight loop; drawing uniforms in blocks keeps every draw seeded by the injected generator and
makes one draw about as cheap as a list index.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeVar

import numpy as np

T = TypeVar("T")

_BLOCK = 1024


class Dice:
    """Uniform choices drawn, a block at a time, from ``rng``."""

    __slots__ = ("_block", "_i", "_rng")

    def __init__(self, rng: np.random.Generator) -> None:
        self._rng = rng
        self._block: list[float] = []
        self._i = 0

    def uniform(self) -> float:
        """A float in [0, 1)."""
        i = self._i
        if i >= len(self._block):
            self._block = self._rng.random(_BLOCK).tolist()
            i = 0
        self._i = i + 1
        return self._block[i]

    def choice(self, items: Sequence[T]) -> T:
        """One of ``items`` (non-empty), uniformly."""
        if len(items) == 1:
            return items[0]
        return items[int(self.uniform() * len(items))]
