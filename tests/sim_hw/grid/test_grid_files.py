"""Grid files: text and JSON parse, and every error names the file, the line/field and the fault."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sim_hw.grid import GridFileError, load_grid, load_layout, parse_json, parse_text


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


@pytest.mark.parametrize(
    ("text", "where", "problem"),
    [
        ("", "line 1", "empty grid file"),
        ("#..\n#.\n", "line 2", "row has 2 cells, expected 3"),
        ("#..\n.x.\n", "line 2, column 2", "unexpected character 'x'"),
        ("B..\n..B\n", "line 2, column 3", "second base"),
    ],
)
def test_text_errors_are_precise(tmp_path: Path, text: str, where: str, problem: str) -> None:
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(GridFileError) as err:
        load_layout(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: {where}: ")
    assert problem in msg
    assert isinstance(err.value, ValueError)
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


@pytest.mark.parametrize(
    ("doc", "where", "problem"),
    [
        ('{"cells": [[0, 1],\n  [0, ]]}', "line 2", "invalid JSON"),
        ("[1, 2]", "top level", "expected a JSON object"),
        ('{"cell_size": 1}', "field 'cells'", "missing"),
        ('{"cells": [[0, 1], [0]]}', "field 'cells[1]'", "row has 1 cells, expected 2"),
        ('{"cells": [[0, 2]]}', "field 'cells[0][1]'", "expected 0 or 1, got 2"),
        ('{"cells": [[0]], "cell_size": -1}', "field 'cell_size'", "positive number"),
        ('{"cells": [[0, 1]], "base": [0, 1]}', "field 'base'", "is an obstacle"),
        ('{"cells": [[0, 1]], "base": [3, 0]}', "field 'base'", "outside"),
        ('{"cells": [[0, 0]], "resources": [[0, 0, 0]]}', "field 'resources[0]'", "positive"),
    ],
)
def test_json_errors_are_precise(doc: str, where: str, problem: str) -> None:
    with pytest.raises(GridFileError) as err:
        parse_json(doc, "arena.json")
    msg = str(err.value)
    assert msg.startswith(f"arena.json: {where}: "), msg
    assert problem in msg
