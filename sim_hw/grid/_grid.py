"""The static grid: which cells are obstacles, 4-neighbourhoods, and the wavefront (BFS) distance.

Cells are addressed as (row, column) or as a flat index ``row * width + column``. The outside of
the rectangle counts as obstacle.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

from robots.grid_hal import OFFSETS

Cell = tuple[int, int]

#: (row, column) offsets of the 4 neighbours, in the order north, east, south, west.
OFFSETS4: tuple[Cell, ...] = OFFSETS[:4]
#: The 8-neighbourhood (4 sides then 4 diagonals), as the grid HAL numbers directions.
OFFSETS8: tuple[Cell, ...] = OFFSETS


class Grid:
    """An immutable rectangle of free and obstacle cells with a physical cell size (metres)."""

    __slots__ = ("_obstacles", "cell_size")

    def __init__(self, obstacles: np.ndarray | list[list[int]], cell_size: float = 1.0) -> None:
        arr = np.array(obstacles, dtype=bool)
        if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
            raise ValueError(f"obstacles must be a non-empty 2-D array, got shape {arr.shape}")
        if not cell_size > 0:
            raise ValueError(f"cell_size must be positive, got {cell_size}")
        arr.setflags(write=False)
        self._obstacles = arr
        self.cell_size = float(cell_size)

    @property
    def obstacles(self) -> np.ndarray:
        """Read-only boolean array (height, width), True where a cell is an obstacle."""
        return self._obstacles

    @property
    def height(self) -> int:
        """Number of rows."""
        return int(self._obstacles.shape[0])

    @property
    def width(self) -> int:
        """Number of columns."""
        return int(self._obstacles.shape[1])

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width)."""
        return self.height, self.width

    @property
    def density(self) -> float:
        """Fraction of cells that are obstacles."""
        return float(self._obstacles.mean())

    def inside(self, cell: Cell) -> bool:
        """Whether ``cell`` lies in the rectangle."""
        r, c = cell
        return 0 <= r < self.height and 0 <= c < self.width

    def is_free(self, cell: Cell) -> bool:
        """Whether ``cell`` is inside and not an obstacle."""
        return self.inside(cell) and not self._obstacles[cell]

    def index(self, cell: Cell) -> int:
        """Flat index of ``cell``."""
        return cell[0] * self.width + cell[1]

    def cell(self, index: int) -> Cell:
        """(row, column) of a flat index."""
        return divmod(index, self.width)

    def neighbours(self, cell: Cell, eight: bool = False) -> list[Cell]:
        """Free neighbours of ``cell`` (4-neighbourhood, or 8 with ``eight``)."""
        r, c = cell
        return [
            (r + dr, c + dc)
            for dr, dc in (OFFSETS8 if eight else OFFSETS4)
            if self.is_free((r + dr, c + dc))
        ]

    def distances(self, source: Cell) -> np.ndarray:
        """Wavefront distance from ``source`` (Simonin et al., Algorithm 1 — a BFS).

        An int array (height, width): the 4-connected path length to ``source``, -1 where
        unreachable or an obstacle.
        """
        if not self.is_free(source):
            raise ValueError(f"source {source} is not a free cell")
        h, w = self.shape
        free = (~self._obstacles).ravel().tolist()
        dist = [-1] * (h * w)
        s = source[0] * w + source[1]
        dist[s] = 0
        queue = deque([s])
        while queue:
            i = queue.popleft()
            d = dist[i] + 1
            r, c = divmod(i, w)
            for j, ok in ((i - w, r > 0), (i + 1, c < w - 1), (i + w, r < h - 1), (i - 1, c > 0)):
                if ok and free[j] and dist[j] < 0:
                    dist[j] = d
                    queue.append(j)
        return np.array(dist, dtype=np.int64).reshape(h, w)

    def reachable(self, source: Cell) -> np.ndarray:
        """Boolean array: free cells connected to ``source`` by 4-moves."""
        return self.distances(source) >= 0

    def to_dict(self) -> dict[str, Any]:
        """A msgpack/JSON-able form: ``{"cells": [[0/1, ...], ...], "cell_size": float}``."""
        return {"cells": self._obstacles.astype(np.uint8).tolist(), "cell_size": self.cell_size}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Grid:
        """Inverse of :meth:`to_dict`."""
        return cls(np.array(data["cells"], dtype=bool), float(data.get("cell_size", 1.0)))

    def to_text(self) -> str:
        """The ``#``/``.`` text form, one line per row."""
        return "\n".join("".join("#" if x else "." for x in row) for row in self._obstacles) + "\n"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Grid):
            return NotImplemented
        return self.cell_size == other.cell_size and np.array_equal(
            self._obstacles, other._obstacles
        )

    def __hash__(self) -> int:
        return hash((self.shape, self._obstacles.tobytes(), self.cell_size))

    def __repr__(self) -> str:
        return f"Grid({self.height}x{self.width}, density={self.density:.3f})"
