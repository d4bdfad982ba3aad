"""What an agent expects to see: the star sensor applied to its own map.

Section III-A: 8 rays (4 straight, 4 diagonal), 2 cells long, each stopped by an obstacle.
``unexplored_in_view`` is Unex(x, r) of equation (3) for every cell x at once.
"""

from __future__ import annotations

import numpy as np

from robots.grid_hal import OBSTACLE
from robots.grid_hal import STAR_RAYS as RAYS

from ._grid import UNKNOWN


def unexplored_in_view(known: np.ndarray, reach: int = 2) -> np.ndarray:
    """For every cell, how many unknown cells its star sensor would cover on this map.

    A ray passes unknown and free cells and stops at a known obstacle (which it counts only if
    unknown, i.e. never), as the reference's ``calculate_utility_jgr`` does. Beyond the map
    counts as obstacle.
    """
    rows, cols = known.shape
    padded = np.full((rows + 2 * reach, cols + 2 * reach), OBSTACLE, dtype=known.dtype)
    padded[reach:-reach, reach:-reach] = known
    unknown = padded == UNKNOWN
    blocked = padded == OBSTACLE
    count = np.zeros(known.shape, dtype=np.int32)
    open_ray = np.empty(known.shape, dtype=bool)
    for dr, dc in RAYS:
        open_ray[:] = True
        for k in range(1, reach + 1):
            r0, c0 = reach + k * dr, reach + k * dc  # the cell k steps along the ray, as views
            count += open_ray & unknown[r0 : r0 + rows, c0 : c0 + cols]
            open_ray &= ~blocked[r0 : r0 + rows, c0 : c0 + cols]
    return count
