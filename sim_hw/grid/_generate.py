"""Seeded generators of grids: random obstacle fields, mazes, double corridors; resource placement.

Every generator takes ``seed`` (an int, a ``numpy.random.Generator`` or None) and is a pure
function of it: the same seed gives the same grid.
"""

from __future__ import annotations

import numpy as np

from sim_hw.grid._grid import Cell, Grid

Seed = int | np.random.Generator | np.random.SeedSequence | None


def _rng(seed: Seed) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def random_obstacles(
    height: int,
    width: int,
    density: float,
    seed: Seed = None,
    *,
    keep_free: tuple[Cell, ...] = (),
    connected: bool = True,
    cell_size: float = 1.0,
) -> Grid:
    """Obstacles on ``round(density * cells)`` cells drawn uniformly (Simonin et al., 4.5 (i)).

    ``keep_free`` cells (e.g. the base) are never obstacles. With ``connected``, free cells that
    cannot be reached from ``keep_free[0]`` (or from the largest free region when ``keep_free`` is
    empty) are then filled, so that every free cell — every possible resource location — is
    reachable, as the paper's foraging setups need; the density then ends slightly above
    ``density`` (``Grid.density`` tells by how much).
    """
    if not 0.0 <= density < 1.0:
        raise ValueError(f"density must be in [0, 1), got {density}")
    rng = _rng(seed)
    n = height * width
    keep = {r * width + c for r, c in keep_free}
    candidates = np.array([i for i in range(n) if i not in keep], dtype=np.int64)
    k = min(round(density * n), len(candidates))
    obst = np.zeros(n, dtype=bool)
    obst[rng.choice(candidates, size=k, replace=False)] = True
    grid = Grid(obst.reshape(height, width), cell_size)
    if not connected:
        return grid
    root: tuple[int, int] | None
    if keep_free:
        root = keep_free[0]
    else:
        root = _largest_region_cell(grid)
        if root is None:
            return grid
    return Grid(~grid.reachable(root), cell_size)


def _largest_region_cell(grid: Grid) -> Cell | None:
    """A cell of the largest 4-connected free region, or None if all cells are obstacles."""
    seen = np.zeros(grid.shape, dtype=bool)
    best: tuple[int, Cell] | None = None
    for r, c in zip(*np.nonzero(~grid.obstacles), strict=True):
        if seen[r, c]:
            continue
        region = grid.reachable((int(r), int(c)))
        seen |= region
        size = int(region.sum())
        if best is None or size > best[0]:
            best = (size, (int(r), int(c)))
    return None if best is None else best[1]


def maze(height: int, width: int, seed: Seed = None, cell_size: float = 1.0) -> Grid:
    """A perfect maze (recursive backtracker) with corridors one cell wide.

    ``height`` and ``width`` must be odd and at least 3; corridor cells have odd coordinates, so
    there is exactly one path between any two free cells.
    """
    if height < 3 or width < 3 or height % 2 == 0 or width % 2 == 0:
        raise ValueError(f"maze sides must be odd and >= 3, got {height}x{width}")
    rng = _rng(seed)
    obst = np.ones((height, width), dtype=bool)
    start = (1, 1)
    obst[start] = False
    stack = [start]
    while stack:
        r, c = stack[-1]
        options = [
            (r + 2 * dr, c + 2 * dc, dr, dc)
            for dr, dc in ((-1, 0), (0, 1), (1, 0), (0, -1))
            if 0 < r + 2 * dr < height - 1
            and 0 < c + 2 * dc < width - 1
            and obst[r + 2 * dr, c + 2 * dc]
        ]
        if not options:
            stack.pop()
            continue
        nr, nc, dr, dc = options[int(rng.integers(len(options)))]
        obst[r + dr, c + dc] = False
        obst[nr, nc] = False
        stack.append((nr, nc))
    return Grid(obst, cell_size)


def double_corridor(
    length: int, corridor_width: int = 1, wall: int = 1, cell_size: float = 1.0
) -> Grid:
    """Two parallel corridors of ``length`` cells joined at both ends into a loop.

    Layout (corridor_width=1, wall=1)::

        #########
        #.......#
        #.#####.#
        #.......#
        #########

    Deterministic: it has no seed.
    """
    if length < 3 or corridor_width < 1 or wall < 1:
        raise ValueError("length >= 3, corridor_width >= 1 and wall >= 1 are needed")
    h = 2 * corridor_width + wall + 2
    w = length + 2
    obst = np.ones((h, w), dtype=bool)
    obst[1 : h - 1, 1 : w - 1] = False
    obst[
        1 + corridor_width : 1 + corridor_width + wall, 1 + corridor_width : w - 1 - corridor_width
    ] = True
    return Grid(obst, cell_size)


def place_resources(
    grid: Grid,
    count: int,
    quantity: int,
    seed: Seed = None,
    *,
    exclude: tuple[Cell, ...] = (),
    reachable_from: Cell | None = None,
) -> dict[Cell, int]:
    """``count`` distinct free cells drawn uniformly, each holding ``quantity`` units.

    ``exclude`` cells (e.g. the base) are never drawn; with ``reachable_from`` only cells
    connected to that cell are drawn.
    """
    rng = _rng(seed)
    ok = ~grid.obstacles if reachable_from is None else grid.reachable(reachable_from)
    ok = ok.copy()
    for cell in exclude:
        ok[cell] = False
    flat = np.flatnonzero(ok.ravel())
    if count > len(flat):
        raise ValueError(f"only {len(flat)} cells available for {count} resources")
    chosen = rng.choice(flat, size=count, replace=False)
    return {grid.cell(int(i)): int(quantity) for i in sorted(chosen.tolist())}
