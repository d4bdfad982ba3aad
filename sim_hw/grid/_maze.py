"""Maze worlds for distributed exploration: generation, files, the star sensor, moves.

Linardakis et al., CU-LVP maze exploration, section IV-A: a
recursive-backtracker maze whose free cells also open their four neighbours with probability
``1 - obstacle_probability``, with a wall on the border. A "30x30" maze is a 31x31 grid
(15x15 backtracker cells, corridors and walls one cell wide), i.e. 29x29 inner cells.
Obstacle probability 0.85 gives the corridor-like maze, 0.15 the nearly open one.

As the authors' reference generator does, a cell whose four neighbours are all walls has them
cleared (so that no wall block is left that no agent can see, and no agent is boxed in); the
border is then walled again.

Cells: 0 free, 1 obstacle. Positions are ``(row, col)``. This module is the simulated hardware
side: the ground truth, the range-2 star sensor (section III-A), the radio's reach (III-B);
the agents' cells and moves are an exclusive :class:`~sim_hw.grid.GridWorld` (:func:`maze_world`).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mover._tables import Table, json_table, matrix, read_text, shown
from robots.grid_hal import FREE, OBSTACLE
from robots.grid_hal import STAR_RAYS as RAYS
from sim_hw.grid._errors import MazeFileError as MazeFileError  # its home before the tree
from sim_hw.grid._grid import Grid
from sim_hw.grid._io import MAX_FILE_BYTES, MAX_SIDE, free_cell
from sim_hw.grid._world import GridWorld

_STEPS = ((0, 1), (1, 0), (0, -1), (-1, 0))


@dataclass
class Maze:
    """A maze grid (0 free, 1 obstacle) and the agents' start cells, in order."""

    grid: np.ndarray
    starts: list[tuple[int, int]] = field(default_factory=list)

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the grid, border included."""
        return (int(self.grid.shape[0]), int(self.grid.shape[1]))


def generate_maze(
    size: int | tuple[int, int],
    obstacle_probability: float,
    rng: np.random.Generator,
    n_starts: int = 20,
) -> Maze:
    """A seeded maze as in section IV-A, with ``n_starts`` distinct random free start cells.

    ``size`` is the paper's nominal size (30 for "30x30"); the grid is ``2*(size//2)+1`` wide.
    """
    rows, cols = (size, size) if isinstance(size, int) else size
    if rows < 4 or cols < 4:
        raise ValueError(f"maze size must be at least 4x4, got {rows}x{cols}")
    if not 0.0 <= obstacle_probability <= 1.0:
        raise ValueError(f"obstacle probability must be in [0, 1], got {obstacle_probability}")
    grid = _backtracker(rows // 2, cols // 2, rng)
    # Section IV-A: each free cell opens its 4 neighbours with probability 1 - p.
    opened = (grid == FREE) & (rng.random(grid.shape) >= obstacle_probability)
    grid[1:, :][opened[:-1, :]] = FREE
    grid[:-1, :][opened[1:, :]] = FREE
    grid[:, 1:][opened[:, :-1]] = FREE
    grid[:, :-1][opened[:, 1:]] = FREE
    _wall_border(grid)
    _clear_enclosed(grid)
    _wall_border(grid)
    return Maze(grid, random_starts(grid, n_starts, rng))


def _backtracker(rc: int, cc: int, rng: np.random.Generator) -> np.ndarray:
    """A perfect maze by recursive backtracking over ``rc x cc`` cells (iterative DFS)."""
    grid = np.ones((2 * rc + 1, 2 * cc + 1), dtype=np.int8)
    grid[1, 1] = FREE
    stack = [(0, 0)]
    while stack:
        x, y = stack[-1]
        for k in rng.permutation(4):
            dx, dy = _STEPS[k]
            nx, ny = x + dx, y + dy
            if 0 <= nx < rc and 0 <= ny < cc and grid[2 * nx + 1, 2 * ny + 1] == OBSTACLE:
                grid[2 * nx + 1, 2 * ny + 1] = FREE
                grid[2 * x + 1 + dx, 2 * y + 1 + dy] = FREE
                stack.append((nx, ny))
                break
        else:
            stack.pop()
    return grid


def _wall_border(grid: np.ndarray) -> None:
    grid[0, :] = OBSTACLE
    grid[-1, :] = OBSTACLE
    grid[:, 0] = OBSTACLE
    grid[:, -1] = OBSTACLE


def _clear_enclosed(grid: np.ndarray) -> None:
    """Clear the 4 walls around any cell walled on all 4 sides (reference generator)."""
    rows, cols = grid.shape
    for i in range(1, rows - 1):
        for j in range(1, cols - 1):
            if grid[i - 1, j] and grid[i + 1, j] and grid[i, j - 1] and grid[i, j + 1]:
                grid[i - 1, j] = grid[i + 1, j] = grid[i, j - 1] = grid[i, j + 1] = FREE


def random_starts(grid: np.ndarray, n: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    """``n`` distinct free cells chosen at random (fewer if the maze has fewer free cells)."""
    free = np.argwhere(grid == FREE)
    pick = rng.choice(len(free), size=min(n, len(free)), replace=False)
    return [(int(free[k][0]), int(free[k][1])) for k in pick]


def star_view(grid: np.ndarray, pos: tuple[int, int], reach: int = 2) -> list[tuple[int, int, int]]:
    """What the star sensor sees from ``pos``: ``(row, col, value)`` triples.

    Section III-A: 8 rays (4 straight, 4 diagonal) up to ``reach`` cells; a ray stops at the
    first obstacle, which it records. The agent's own cell is included.
    """
    rows, cols = grid.shape
    r0, c0 = pos
    seen = [(r0, c0, int(grid[r0, c0]))]
    for dr, dc in RAYS:
        for k in range(1, reach + 1):
            r, c = r0 + k * dr, c0 + k * dc
            if not (0 <= r < rows and 0 <= c < cols):
                break
            v = int(grid[r, c])
            seen.append((r, c, v))
            if v == OBSTACLE:
                break
    return seen


def observable(grid: np.ndarray, starts: Iterable[tuple[int, int]], reach: int = 2) -> np.ndarray:
    """Inner cells a star view of ``reach`` sees from some free cell reachable from a start.

    The observer's measure of a complete exploration (the border never counts).
    """
    rows, cols = grid.shape
    seen = np.zeros(grid.shape, dtype=bool)
    if reach <= 0:
        return seen
    reached = np.zeros(grid.shape, dtype=bool)
    todo = list(starts)
    for s in todo:
        reached[s] = True
    while todo:
        r, c = todo.pop()
        for rr, cc, _ in star_view(grid, (r, c), reach):
            seen[rr, cc] = True
        for nr, nc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
            if 0 <= nr < rows and 0 <= nc < cols and grid[nr, nc] == FREE and not reached[nr, nc]:
                reached[nr, nc] = True
                todo.append((nr, nc))
    seen[0, :] = seen[-1, :] = seen[:, 0] = seen[:, -1] = False
    return seen


def broadcast_range(shape: tuple[int, int]) -> int:
    """Section III-B: 25 % of the maze's larger side, in cells (7 for a 31x31 grid)."""
    return int(0.25 * max(shape))


def maze_world(maze: Maze, n_agents: int) -> GridWorld:
    """The grid world of ``maze`` with ``n_agents`` on its first starts: exclusive cells (a move
    into an occupied cell fails, section III-A), the first start standing in for the base.
    Who hears whom: ``world.neighbours(i, broadcast_range(maze.shape), "manhattan")``."""
    if not 0 < n_agents <= len(maze.starts):
        raise ValueError(f"{n_agents} agents but the maze has {len(maze.starts)} starts")
    starts = [(int(r), int(c)) for r, c in maze.starts[:n_agents]]
    return GridWorld(Grid(maze.grid == OBSTACLE), starts[0], starts=starts, exclusive=True)


def save_maze(path: str | Path, maze: Maze) -> None:
    """Write ``{"grid": [[0,1,...],...], "starts": [[row, col], ...]}``."""
    data = {"grid": maze.grid.astype(int).tolist(), "starts": [list(s) for s in maze.starts]}
    Path(path).write_text(json.dumps(data))


def load_maze(path: str | Path) -> Maze:
    """Read a maze JSON file; raise :class:`MazeFileError` naming the file, key and fault."""
    p = Path(path)
    t = json_table(
        read_text(p, MazeFileError, most=MAX_FILE_BYTES, form="JSON"), str(p), MazeFileError
    )
    grid = np.array(matrix(t, "grid", (FREE, OBSTACLE), most=MAX_SIDE), dtype=np.int8)
    rows, cols = grid.shape
    if rows < 3 or cols < 3:
        raise t.fail("grid", f"must be at least 3×3 cells, got {rows}×{cols}")
    if not (grid[0].all() and grid[-1].all() and grid[:, 0].all() and grid[:, -1].all()):
        raise t.fail("grid", "must have obstacles (1) all along its border")
    starts = _starts(t, grid)
    t.done()
    return Maze(grid, starts)


def _starts(t: Table, grid: np.ndarray) -> list[tuple[int, int]]:
    raw = t.get("starts") or []
    if not isinstance(raw, list) or len(raw) > grid.size:
        raise t.fail(
            "starts", f"must be a list of [row, col], at most one a cell, got {shown(raw)}"
        )
    starts: list[tuple[int, int]] = []
    for k, s in enumerate(raw):
        cell = free_cell(t, ("starts", k), s, grid == OBSTACLE)
        if cell in starts:
            raise t.fail(("starts", k), f"{list(cell)} repeats starts[{starts.index(cell)}]")
        starts.append(cell)
    return starts
