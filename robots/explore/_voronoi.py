"""Geodesic Voronoi partition of the maze among the agents (section III-B).

Every agent computes the same partition from what all agents know at the start (the team's
start cells and the walled border; everything else unknown, counted as free, as the paper's
Fig. 4 says), so no agent needs a central map to know the regions.
"""

from __future__ import annotations

import numpy as np


def voronoi_partition(passable: np.ndarray, seeds: list[tuple[int, int]]) -> np.ndarray:
    """Label each passable cell with the index of its geodesically nearest seed.

    Multi-source wavefront (4-connected); a cell at equal distance from several seeds goes to
    the seed whose wave reached it first in index order. Unreachable or blocked cells get -1.
    """
    rows, cols = passable.shape
    flat = passable.ravel()
    label = np.full(rows * cols, -1, dtype=np.int16)
    level = []
    for i, (r, c) in enumerate(seeds):
        k = r * cols + c
        if label[k] < 0:
            label[k] = i
            level.append(k)
    lab = label.tolist()
    while level:
        nxt = []
        for k in level:
            r, c = divmod(k, cols)
            for m, ok in (
                (k - cols, r > 0),
                (k + cols, r < rows - 1),
                (k - 1, c > 0),
                (k + 1, c < cols - 1),
            ):
                if ok and lab[m] < 0 and flat[m]:
                    lab[m] = lab[k]
                    nxt.append(m)
        level = nxt
    return np.array(lab, dtype=np.int16).reshape(rows, cols)
