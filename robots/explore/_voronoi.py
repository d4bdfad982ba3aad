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
            for m in _neighbours(k, rows, cols):
                if lab[m] < 0 and flat[m]:
                    lab[m] = lab[k]
                    nxt.append(m)
        level = nxt
    return np.array(lab, dtype=np.int16).reshape(rows, cols)


def _neighbours(k: int, rows: int, cols: int) -> list[int]:
    """Cell ``k``'s 4-connected neighbours on a ``rows`` x ``cols`` grid (flat indices), in
    the order up, down, left, right."""
    r, c = divmod(k, cols)
    out = []
    if r > 0:
        out.append(k - cols)
    if r < rows - 1:
        out.append(k + cols)
    if c > 0:
        out.append(k - 1)
    if c < cols - 1:
        out.append(k + 1)
    return out


def _geodesic(flat: list[bool], start: int, rows: int, cols: int) -> list[int]:
    """4-connected wavefront distances from ``start`` over ``flat`` cells (-1 unreached)."""
    dist = [-1] * (rows * cols)
    dist[start] = 0
    level = [start]
    d = 0
    while level:
        d += 1
        nxt = []
        for k in level:
            for m in _neighbours(k, rows, cols):
                if dist[m] < 0 and flat[m]:
                    dist[m] = d
                    nxt.append(m)
        level = nxt
    return dist


BALANCE_ROUNDS = 100  # weight updates of :func:`balanced_partition`
BALANCE_GAIN = 2.0  # first weight step, in cells, per region size off the mean (relative)


def balanced_partition(passable: np.ndarray, seeds: list[tuple[int, int]]) -> np.ndarray:
    """Like :func:`voronoi_partition`, but with regions of more equal size.

    Each seed's geodesic distance is lowered by a weight (an additively weighted Voronoi
    partition); the weights are raised for regions smaller than the mean and lowered for
    larger ones, in ``BALANCE_ROUNDS`` shrinking steps, and the partition whose largest region
    was smallest (of those where every seed keeps its own cell; the first is the plain one) is
    kept. A cell belongs to the seed with the least weighted distance (ties: the lower index),
    so each region is still connected along shortest paths to its seed. Every agent computes
    the same partition from the same start cells. Additive weights cannot split a corridor
    between seeds in a row (a seed's whole far side changes hands at once): there the plain
    partition stays.

    Why: from random starts the plain regions are very unequal (8 agents in a 30x30 maze: the
    largest is often twice the mean), and the team is done only when the largest region is,
    the other agents walking far to help with it.
    """
    rows, cols = passable.shape
    flat = passable.ravel().tolist()
    starts = [r * cols + c for r, c in seeds]
    dist = np.array([_geodesic(flat, s, rows, cols) for s in starts], dtype=float)
    reached = dist >= 0
    dist[~reached] = np.inf
    inside = reached.any(axis=0)
    mean = max(1.0, float(inside.sum()) / len(seeds))
    weight = np.zeros(len(seeds))
    best: tuple[int, np.ndarray] | None = None
    for t in range(BALANCE_ROUNDS):
        label = np.argmin(dist - weight[:, None], axis=0)  # first minimum: lower index
        size = np.bincount(label[inside], minlength=len(seeds))
        own = all(label[k] == i for i, k in enumerate(starts))  # each seed keeps its cell
        if own and (best is None or int(size.max()) < best[0]):
            best = (int(size.max()), label)
        weight += BALANCE_GAIN * (mean - size) / mean / (1 + t / 10)
    assert best is not None  # the plain partition (all weights 0) keeps every seed's cell
    return np.where(inside, best[1], -1).astype(np.int16).reshape(rows, cols)
