"""Grid files: text (``#``/``.`` or ``1``/``0`` per cell, one line per row) and JSON.

Text files may also hold ``B`` (the base, a free cell) and ``R`` (a resource, a free cell whose
quantity is ``default_quantity``). JSON files hold an object::

    {"cells": [[0, 1, ...], ...], "cell_size": 0.5,
     "base": [row, col], "resources": [[row, col, quantity], ...]}

where only ``cells`` is required. Every error is a :class:`GridFileError` naming the file, the line
(text) or field (JSON), and what is wrong.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sim_hw.grid._errors import GridFileError
from sim_hw.grid._grid import Cell, Grid

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
        raise GridFileError(source, "line 1", "empty grid file")
    width = len(lines[0].rstrip())
    rows: list[list[bool]] = []
    base: Cell | None = None
    resources: dict[Cell, int] = {}
    for r, raw in enumerate(lines):
        line = raw.rstrip()
        where = f"line {r + 1}"
        if len(line) != width:
            raise GridFileError(source, where, f"row has {len(line)} cells, expected {width}")
        row: list[bool] = []
        for c, ch in enumerate(line):
            if ch not in _OBSTACLE and ch not in _FREE:
                raise GridFileError(
                    source,
                    f"{where}, column {c + 1}",
                    f"unexpected character {ch!r} (expected '#'/'.', '1'/'0', 'B' or 'R')",
                )
            row.append(ch in _OBSTACLE)
            if ch == "B":
                if base is not None:
                    raise GridFileError(source, f"{where}, column {c + 1}", "second base 'B'")
                base = (r, c)
            elif ch == "R":
                resources[(r, c)] = default_quantity
        rows.append(row)
    return Layout(Grid(np.array(rows, dtype=bool)), base, resources)


def _cell_field(source: str, name: str, value: Any, grid: Grid) -> Cell:
    """Check a [row, col] field against the grid."""
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, int) and not isinstance(v, bool) for v in value)
    ):
        raise GridFileError(
            source, f"field {name!r}", f"expected [row, col] integers, got {value!r}"
        )
    cell = (value[0], value[1])
    if not grid.inside(cell):
        raise GridFileError(source, f"field {name!r}", f"cell {list(cell)} is outside {grid.shape}")
    if not grid.is_free(cell):
        raise GridFileError(source, f"field {name!r}", f"cell {list(cell)} is an obstacle")
    return cell


def parse_json(text: str, source: str = "<json>") -> Layout:
    """Parse the JSON form; ``source`` names the file in errors."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise GridFileError(source, f"line {exc.lineno}", f"invalid JSON: {exc.msg}") from None
    if not isinstance(data, dict):
        raise GridFileError(source, "top level", "expected a JSON object")
    if "cells" not in data:
        raise GridFileError(source, "field 'cells'", "missing")
    cells = data["cells"]
    if not isinstance(cells, list) or not cells or not isinstance(cells[0], list):
        raise GridFileError(source, "field 'cells'", "expected a non-empty list of rows")
    width = len(cells[0])
    for r, row in enumerate(cells):
        if not isinstance(row, list) or len(row) != width:
            n = len(row) if isinstance(row, list) else type(row).__name__
            raise GridFileError(
                source, f"field 'cells[{r}]'", f"row has {n} cells, expected {width}"
            )
        for c, v in enumerate(row):
            if v not in (0, 1) or isinstance(v, float):
                raise GridFileError(
                    source, f"field 'cells[{r}][{c}]'", f"expected 0 or 1, got {v!r}"
                )
    size = data.get("cell_size", 1.0)
    if isinstance(size, bool) or not isinstance(size, int | float) or not size > 0:
        raise GridFileError(
            source, "field 'cell_size'", f"expected a positive number, got {size!r}"
        )
    grid = Grid(np.array(cells, dtype=bool), float(size))
    base = _cell_field(source, "base", data["base"], grid) if "base" in data else None
    resources: dict[Cell, int] = {}
    for k, item in enumerate(data.get("resources", [])):
        name = f"resources[{k}]"
        if not isinstance(item, list) or len(item) != 3:
            raise GridFileError(
                source, f"field {name!r}", f"expected [row, col, quantity], got {item!r}"
            )
        cell = _cell_field(source, name, item[:2], grid)
        q = item[2]
        if isinstance(q, bool) or not isinstance(q, int) or q <= 0:
            raise GridFileError(
                source, f"field {name!r}", f"quantity must be a positive integer, got {q!r}"
            )
        resources[cell] = q
    return Layout(grid, base, resources)


def load_layout(path: str | Path, default_quantity: int = 1) -> Layout:
    """Read a grid file (``.json`` as JSON, anything else as text)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise GridFileError(str(p), "content", f"not UTF-8 text ({exc.reason})") from None
    if p.suffix.lower() == ".json":
        return parse_json(text, str(p))
    return parse_text(text, str(p), default_quantity)


def load_grid(path: str | Path) -> Grid:
    """Read only the grid of a grid file."""
    return load_layout(path).grid
