"""Grid files: text and JSON parse, and every error names the file, the line/field and the fault."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mover import ConfigError
from sim_hw.grid import GridFileError, load_grid, load_layout, parse_text


def test_text_hash_dot_and_markers() -> None:
    lay = parse_text("#..\n.B.\nR.#\n", default_quantity=7)
    assert lay.grid.obstacles.tolist() == [[1, 0, 0], [0, 0, 0], [0, 0, 1]]
    assert lay.base == (1, 1)
    assert lay.resources == {(2, 0): 7}


def test_text_zero_one_equals_hash_dot() -> None:
    assert parse_text("100\n001\n").grid == parse_text("#..\n..#\n").grid


def test_text_round_trip(tmp_path: Path) -> None:
    grid = parse_text("#.#\n...\n").grid
    path = tmp_path / "g.txt"
    path.write_text(grid.to_text())
    assert load_grid(path) == grid


MISTAKES = {
    ".txt": [
        ("", "", "is empty: a grid file needs at least one row"),
        ("#..\n#.\n", ":2", "must be a row of 3 cells (as line 1), got 2"),
        ("#..\n.x.\n", ":2: column 2", "must be '#' or '.', '1' or '0', 'B' or 'R', got 'x'"),
        ("B..\n..B\n", ":2: column 3", "a second base 'B' (the first is at line 1, column 1)"),
    ],
    ".json": [
        ('{"cells": [[0, 1],\n  [0, ]]}', ":2", "not valid JSON: Expecting value (column 7)"),
        ("[1, 2]", "", "must be a JSON object, got [1, 2]"),
        ('{"cell_size": 1}', ": cells", "is required (a list of rows)"),
        ('{"cells": [[0, 1], [0]]}', ": cells[1]", "must be a row of 2 cells (as row 0), got 1"),
        ('{"cells": [[0, 2]]}', ": cells[0][1]", "must be 0 or 1, got 2"),
        (
            '{"cells": [[0]], "cell_size": -1}',
            ": cell_size",
            "must be > 0 and at most 1000000, got -1",
        ),
        ('{"cells": [[0, 1]], "base": [0, 1]}', ": base", "[0, 1] is an obstacle"),
        ('{"cells": [[0, 1]], "base": [3, 0]}', ": base", "[3, 0] is outside the 1×2 grid"),
        (
            '{"cells": [[0, 0]], "resources": [[0, 0, 0]]}',
            ": resources[0]",
            "must be [row, col, quantity] (a quantity from 1 to 1000000000), got [0, 0, 0]",
        ),
        (
            '{"cells": [[0]], "cel_size": 2}',
            ": cel_size",
            "unknown key (did you mean 'cell_size'?); known: cells, cell_size, base, resources",
        ),
    ],
}
"""Mistakes in a grid file of each format: its text, where the error says it is (the line,
column or field), and the fault."""


@pytest.mark.parametrize(
    ("suffix", "text", "where", "problem"),
    [(suffix, *mistake) for suffix, mistakes in MISTAKES.items() for mistake in mistakes],
)
def test_errors_are_precise(
    tmp_path: Path, suffix: str, text: str, where: str, problem: str
) -> None:
    """A text or JSON grid file's mistake: the file, the line or field, the fault, exactly."""
    path = tmp_path / f"bad{suffix}"
    path.write_text(text)
    with pytest.raises(GridFileError) as err:
        load_layout(path)
    msg = str(err.value)
    assert msg == f"{path}{where}: {problem}"
    assert isinstance(err.value, ValueError) and isinstance(err.value, ConfigError)
    assert err.value.source == str(path)


def test_json_full(tmp_path: Path) -> None:
    path = tmp_path / "g.json"
    data = {"cells": [[0, 1], [0, 0]], "cell_size": 0.5, "base": [1, 1], "resources": [[0, 0, 9]]}
    path.write_text(json.dumps(data))
    lay = load_layout(path)
    assert lay.grid.cell_size == 0.5
    assert np.array_equal(lay.grid.obstacles, [[False, True], [False, False]])
    assert lay.base == (1, 1)
    assert lay.resources == {(0, 0): 9}
