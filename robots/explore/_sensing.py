"""What an agent expects to see: the star sensor applied to its own map.

Section III-A: 8 rays (4 straight, 4 diagonal), 2 cells long, each stopped by an obstacle.
``unexplored_in_view`` is Unex(x, r) of equation (3) for every cell x at once.
"""

from __future__ import annotations

import numpy as np

from ._grid import OBSTACLE, UNKNOWN

RAYS: tuple[tuple[int, int], ...] = (
    (-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1),
)


def _shifted(a: np.ndarray, dr: int, dc: int, fill: bool) -> np.ndarray:
    """``out[r, c] = a[r + dr, c + dc]`` with ``fill`` outside the array."""
    out = np.full(a.shape, fill, dtype=bool)
    rows, cols = a.shape
    out[max(0, -dr):rows - max(0, dr), max(0, -dc):cols - max(0, dc)] = a[
        max(0, dr):rows - max(0, -dr), max(0, dc):cols - max(0, -dc)
    ]
    return out


def unexplored_in_view(known: np.ndarray, reach: int = 2) -> np.ndarray:
    """For every cell, how many unknown cells its star sensor would cover on this map.

    A ray passes unknown and free cells and stops at a known obstacle (which it counts only if
    unknown, i.e. never), as the reference's ``calculate_utility_jgr`` does.
    """
    unknown = known == UNKNOWN
    obstacle = known == OBSTACLE
    count = np.zeros(known.shape, dtype=np.int32)
    for dr, dc in RAYS:
        open_ray = np.ones(known.shape, dtype=bool)
        for k in range(1, reach + 1):
            count += open_ray & _shifted(unknown, k * dr, k * dc, False)
            open_ray &= ~_shifted(obstacle, k * dr, k * dc, True)
    return count

