"""Cell states and wavefront (BFS) search on an agent's own map.

The map is a numpy ``int8`` array (section IV-A states: -1 unknown, 0 free, 1 obstacle; 2 marks
an agent). Searches run on the flattened map in plain Python over ``bytearray`` masks: for a
31x31 maze this is several times faster than a numpy wavefront, whose cost grows with the
path length in corridor mazes. The border is always a known obstacle, so a search never steps
outside the array.
"""

from __future__ import annotations

import numpy as np

from robots.grid_hal import FREE as FREE
from robots.grid_hal import OBSTACLE as OBSTACLE

UNKNOWN = -1
AGENT = 2


def passable_mask(known: np.ndarray, blocked: list[int] | tuple[int, ...] = ()) -> bytearray:
    """Cells a plan may cross: everything not a known obstacle (unknown counts as free, as in
    the paper's wavefront), minus the flat indices in ``blocked`` (other agents)."""
    mask = bytearray((known.ravel() != OBSTACLE).tobytes())
    for k in blocked:
        mask[k] = 0
    return mask


def wavefront(
    passable: bytearray,
    start: int,
    width: int,
    targets: bytearray | None = None,
    nearest_only: bool = False,
    gain: list[int] | None = None,
) -> tuple[list[int], list[int], list[int]]:
    """Breadth-first wavefront from flat index ``start`` (section III-C, Fig. 2).

    Returns ``(dist, parent, found)``: distances (-1 unreached), BFS parents, and the target
    cells reached. With ``nearest_only`` the search stops after the first level holding a
    target, and ``found`` is that level's targets only (the nearest frontiers).

    With ``gain`` (a value per flat cell) each cell's parent is chosen, among its neighbours
    one level nearer the start, to maximise the gain summed along the path from the start:
    ``path_to`` then returns, of all shortest paths to a cell, one with the most gain.
    """
    n = len(passable)
    dist = [-1] * n
    parent = [-1] * n
    weigh = gain is not None
    g = gain if gain is not None else []
    acc = [0] * n if weigh else []  # gain summed along the chosen path
    dist[start] = 0
    level = [start]
    found: list[int] = []
    offsets = (-width, width, -1, 1)
    d = 0
    while level:
        if targets is not None:
            hits = [c for c in level if targets[c]]
            if hits:
                found.extend(hits)
                if nearest_only:
                    break
        d += 1
        nxt = []
        for c in level:
            for o in offsets:
                m = c + o
                if dist[m] < 0 and passable[m]:
                    dist[m] = d
                    parent[m] = c
                    nxt.append(m)
                    if weigh:
                        acc[m] = acc[c] + g[m]
                elif weigh and dist[m] == d and acc[c] + g[m] > acc[m]:
                    parent[m] = c  # another shortest way in that sees more
                    acc[m] = acc[c] + g[m]
        level = nxt
    return dist, parent, found


def path_to(parent: list[int], start: int, goal: int) -> list[int]:
    """The cells from ``start`` (exclusive) to ``goal`` (inclusive) along BFS parents."""
    path = []
    c = goal
    while c != start and c >= 0:
        path.append(c)
        c = parent[c]
    if c != start:
        return []
    path.reverse()
    return path
