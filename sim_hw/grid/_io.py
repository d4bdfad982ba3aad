"""Grid files: text (``#``/``.`` or ``1``/``0`` per cell, one line per row) and JSON.

Text files may also hold ``B`` (the base, a free cell) and ``R`` (a resource, a free cell whose
quantity is ``default_quantity``). JSON files hold an object::

    {"cells": [[0, 1, ...], ...], "cell_size": 0.5,
     "base": [row, col], "resources": [[row, col, quantity], ...]}

where only ``cells`` is required; JSON files are read by :mod:`mover._tables`. Every error is a
:class:`GridFileError` in the one wording of file errors: the file, the line (text, or JSON that
does not parse), the key (JSON), and what was expected. Sides, counts and quantities are bounded
where they are read.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mover._keylines import Path as KeyPath
from mover._tables import Kind, Table, Wrong, json_table, matrix, number, read_text, shown
from sim_hw.grid._errors import GridFileError
from sim_hw.grid._grid import Cell, Grid

MAX_SIDE = 10_000
"""The most rows, and the most cells in a row, of a grid or maze file."""
MAX_FILE_BYTES = 256 * 2**20
"""The largest grid or maze file read."""
MAX_QUANTITY = 10**9
"""The largest quantity of a resource."""

_OBSTACLE = frozenset("#1")
_FREE = frozenset(".0BR")


@dataclass(frozen=True)
class Layout:
    """A grid with its optional base and resources, as read from a file."""

    grid: Grid
    base: Cell | None = None
    resources: dict[Cell, int] = field(default_factory=dict)


def parse_text(text: str, source: str = "<text>", default_quantity: int = 1) -> Layout:
    """Parse the text form; ``source`` names the file in errors."""
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise GridFileError(source, "", "is empty: a grid file needs at least one row")
    if len(lines) > MAX_SIDE:
        raise GridFileError(source, "", f"must hold at most {MAX_SIDE} rows, got {len(lines)}")
    width = len(lines[0].rstrip())
    rows: list[list[bool]] = []
    base: Cell | None = None
    resources: dict[Cell, int] = {}
    for r, raw in enumerate(lines):
        line = raw.rstrip()
        if len(line) != width or not 0 < width <= MAX_SIDE:
            expected = f"{width} cells (as line 1)" if r else f"1 to {MAX_SIDE} cells"
            raise GridFileError(
                source, "", f"must be a row of {expected}, got {len(line)}", line=r + 1
            )
        row: list[bool] = []
        for c, ch in enumerate(line):
            column = f"column {c + 1}"
            if ch not in _OBSTACLE and ch not in _FREE:
                expected = "'#' or '.', '1' or '0', 'B' or 'R'"
                raise GridFileError(source, column, f"must be {expected}, got {ch!r}", line=r + 1)
            row.append(ch in _OBSTACLE)
            if ch == "B":
                if base is not None:
                    first = f"line {base[0] + 1}, column {base[1] + 1}"
                    problem = f"a second base 'B' (the first is at {first})"
                    raise GridFileError(source, column, problem, line=r + 1)
                base = (r, c)
            elif ch == "R":
                resources[(r, c)] = default_quantity
        rows.append(row)
    return Layout(Grid(np.array(rows, dtype=bool)), base, resources)


def _pair(value: object) -> tuple[int, int]:
    if not (isinstance(value, list) and len(value) == 2 and all(type(v) is int for v in value)):
        raise Wrong(f"must be [row, col] (two integers), got {shown(value)}")
    return (value[0], value[1])


CELL = Kind("[row, col]", _pair)
"""A cell of a file: ``[row, col]``."""


def free_cell(t: Table, key: str | int | KeyPath, value: object, obstacles: np.ndarray) -> Cell:
    """``value`` (at ``key`` of ``t``) as a cell inside the grid of ``obstacles`` and free."""
    cell = t.check(key, value, CELL)
    rows, cols = obstacles.shape
    if not (0 <= cell[0] < rows and 0 <= cell[1] < cols):
        raise t.fail(key, f"{list(cell)} is outside the {rows}×{cols} grid")
    if obstacles[cell]:
        raise t.fail(key, f"{list(cell)} is an obstacle")
    return cell


def _resource(value: object) -> tuple[int, int, int]:
    if isinstance(value, list) and len(value) == 3 and all(type(v) is int for v in value):
        row, col, quantity = value
        if 1 <= quantity <= MAX_QUANTITY:
            return (row, col, quantity)
    raise Wrong(
        f"must be [row, col, quantity] (a quantity from 1 to {MAX_QUANTITY}), got {shown(value)}"
    )


RESOURCE = Kind("[row, col, quantity]", _resource)
"""A resource of a JSON grid file: ``[row, col, quantity]``."""


def parse_json(text: str, source: str = "<json>") -> Layout:
    """Parse the JSON form; ``source`` names the file in errors."""
    t = json_table(text, source, GridFileError)
    cells = matrix(t, "cells", (0, 1), most=MAX_SIDE)
    grid = Grid(np.array(cells, dtype=bool), t.read("cell_size", number(), 1.0))
    written = t.get("base")
    base = None if written is None else free_cell(t, "base", written, grid.obstacles)
    resources: dict[Cell, int] = {}
    items = t.get("resources") or []
    if not isinstance(items, list) or len(items) > grid.obstacles.size:
        problem = f"must be a list of [row, col, quantity], at most one a cell, got {shown(items)}"
        raise t.fail("resources", problem)
    for k, item in enumerate(items):
        row, col, quantity = t.check(("resources", k), item, RESOURCE)
        resources[free_cell(t, ("resources", k), [row, col], grid.obstacles)] = quantity
    t.done()
    return Layout(grid, base, resources)


def load_layout(path: str | Path, default_quantity: int = 1) -> Layout:
    """Read a grid file (``.json`` as JSON, anything else as text)."""
    p = Path(path)
    json = p.suffix.lower() == ".json"
    text = read_text(p, GridFileError, most=MAX_FILE_BYTES, form="JSON" if json else "")
    if json:
        return parse_json(text, str(p))
    return parse_text(text, str(p), default_quantity)


def load_grid(path: str | Path) -> Grid:
    """Read only the grid of a grid file."""
    return load_layout(path).grid
