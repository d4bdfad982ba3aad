"""Geometric sensing on a grid: view rays blocked by obstacles, and range queries."""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from sim_hw.grid._grid import Cell, Grid


def ray_cells(a: Cell, b: Cell) -> Iterator[Cell]:
    """Cells on the Bresenham segment from ``a`` to ``b``, both ends included."""
    r0, c0 = a
    r1, c1 = b
    dr, dc = abs(r1 - r0), abs(c1 - c0)
    sr = 1 if r1 > r0 else -1
    sc = 1 if c1 > c0 else -1
    err = dc - dr
    r, c = r0, c0
    while True:
        yield r, c
        if (r, c) == (r1, c1):
            return
        e2 = 2 * err
        if e2 > -dr:
            err -= dr
            c += sc
        if e2 < dc:
            err += dc
            r += sr


def line_of_sight(grid: Grid, a: Cell, b: Cell) -> bool:
    """Whether no obstacle lies on the view ray between ``a`` and ``b`` (ends excluded)."""
    return all(cell in (a, b) or grid.is_free(cell) for cell in ray_cells(a, b))


def disc_view(grid: Grid, origin: Cell, radius: float) -> list[Cell]:
    """Cells within ``radius`` cells of ``origin`` that a ray from ``origin`` reaches.

    An obstacle cell is visible (it is what the ray hits) but hides what lies behind it.
    """
    r0, c0 = origin
    k = int(radius)
    out = []
    for r in range(max(0, r0 - k), min(grid.height, r0 + k + 1)):
        for c in range(max(0, c0 - k), min(grid.width, c0 + k + 1)):
            if (r - r0) ** 2 + (c - c0) ** 2 <= radius * radius and line_of_sight(
                grid, origin, (r, c)
            ):
                out.append((r, c))
    return out


def hearers(cells: Sequence[Cell], i: int, reach: float, metric: str = "euclid") -> list[int]:
    """Indices of the cells other than ``i`` within ``reach`` cells of cell ``i``: who hears a
    range-limited broadcast from there. ``manhattan`` counts 4-connected steps (as the maze
    reference code measures range), ``euclid`` the straight line."""
    r0, c0 = cells[i]
    if metric == "manhattan":
        near = [abs(r - r0) + abs(c - c0) <= reach for r, c in cells]
    elif metric == "euclid":
        lim = reach * reach
        near = [(r - r0) ** 2 + (c - c0) ** 2 <= lim for r, c in cells]
    else:
        raise ValueError(f"metric must be manhattan or euclid, got {metric!r}")
    return [j for j, ok in enumerate(near) if ok and j != i]


def within_range(
    positions: Sequence[Cell], i: int, radius: float, cell_size: float = 1.0
) -> list[int]:
    """Indices of the agents other than ``i`` within ``radius`` metres of agent ``i``.

    The in-process stand-in for a range-limited broadcast: who hears agent ``i``.
    """
    return hearers(positions, i, radius / cell_size)
