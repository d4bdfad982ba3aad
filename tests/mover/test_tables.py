"""The one table reader: each mistake in one wording, with the file, the line and the key."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from pathlib import Path

import pytest

from mover import ConfigError
from mover._exceptions import FileError
from mover._tables import (
    BOOLEAN,
    NAME,
    STRING,
    Source,
    Table,
    integer,
    json_table,
    matrix,
    number,
    pair,
    read_text,
    string,
    toml_table,
    vector,
)
from mover._up import TeamFileError
from sim_hw import WorldFileError
from sim_hw.grid import GridFileError, MazeFileError

TEXT = """\
[arena]
size = [10, 10]
name = "hall"

[[boxes]]
id = "a"
mass = 2

[[boxes]]
id = "b"
mass = -1
"""


def root() -> Table:
    return toml_table(TEXT, "a.toml", FileError)


def fails(read: Callable[[], object]) -> str:
    """The message of the FileError that ``read`` raises."""
    with pytest.raises(FileError) as caught:
        read()
    return str(caught.value)


def test_an_unknown_key_names_its_line_and_the_closest_known_key() -> None:
    boxes = root().tables("boxes", most=10)
    boxes[0].read("id", STRING)
    boxes[0].read("mas", number(), 1.0)
    with pytest.raises(FileError) as caught:
        boxes[0].done()
    error = caught.value
    assert (
        str(error) == "a.toml:7: boxes[0].mass: unknown key (did you mean 'mas'?); known: id, mas"
    )
    assert (error.source, error.line, error.where) == ("a.toml", 7, "boxes[0].mass")
    arena = root().table("arena")
    assert arena is not None
    message = fails(lambda: arena.only(("sizes", "name"), kind="an arena"))
    assert message == (
        "a.toml:2: arena.size: unknown key in an arena (did you mean 'sizes'?); known: sizes, name"
    )
    assert "did you mean" not in fails(lambda: arena.only(("colour",)))


def test_a_wrong_type_says_what_was_expected_and_what_came() -> None:
    arena = root().table("arena")
    assert arena is not None
    assert fails(lambda: arena.read("name", number())) == (
        "a.toml:3: arena.name: must be a number, got 'hall'"
    )
    assert fails(lambda: arena.read("size", vector(3))) == (
        "a.toml:2: arena.size: must be a list of 3 numbers, got [10, 10]"
    )
    assert fails(lambda: arena.read("name", BOOLEAN)) == (
        "a.toml:3: arena.name: must be true or false, got 'hall'"
    )
    assert fails(lambda: arena.read("name", string(("small", "large")))) == (
        "a.toml:3: arena.name: must be 'small' or 'large', got 'hall'"
    )
    assert fails(lambda: arena.read("size", integer(high=5))) == (
        "a.toml:2: arena.size: must be an integer, got [10, 10]"
    )
    assert fails(lambda: root().read("arena", STRING)).endswith(
        "arena: must be a string, got a table"
    )
    assert (
        fails(lambda: arena.read("missing", NAME))
        == "a.toml:1: arena.missing: is required (a name)"
    )


def test_numbers_are_bounded_where_they_are_read() -> None:
    second = root().tables("boxes", most=10)[1]
    assert fails(lambda: second.read("mass", number())) == (
        "a.toml:11: boxes[1].mass: must be > 0 and at most 1000000, got -1"
    )
    assert second.read("mass", number(low=None)) == -1.0
    assert fails(lambda: second.read("mass", number(strict=False))).endswith(
        "must be from 0 to 1000000, got -1"
    )
    assert fails(lambda: second.read("mass", integer(low=1, high=9))).endswith(
        "must be from 1 to 9, got -1"
    )
    arena = root().table("arena")
    assert arena is not None
    assert arena.read("size", pair(low=0.0, high=10.0)) == (10.0, 10.0)
    assert fails(lambda: arena.read("size", pair(low=0.0, high=5.0))).endswith(
        "arena.size: must be a list of 2 numbers, each > 0 and at most 5, got [10, 10]"
    )
    assert fails(lambda: root().tables("boxes", most=1)) == (
        "a.toml:5: boxes: must hold at most 1 tables, got 2"
    )
    for wrong in (float("nan"), float("inf"), True):
        read = partial(Table({"x": wrong}, Source("s")).read, "x", number())
        assert "must be a number" in fails(read)


def test_defaults_options_and_the_lines_of_nested_keys() -> None:
    top = toml_table('[team]\nname = "a"\n\n[team.sub]\nx = "no"\n', "t.toml", TeamFileError)
    team = top.table("team")
    assert team is not None
    assert team.read("seed", integer(high=9), 3) == 3 and team.option("seed", BOOLEAN) is None
    sub = team.table("sub")
    assert sub is not None
    with pytest.raises(TeamFileError) as caught:
        sub.read("x", integer(high=9))
    assert str(caught.value) == "t.toml:5: team.sub.x: must be an integer, got 'no'"
    assert caught.value.line == 5
    # a key that is not written is found at its table's line
    assert fails(lambda: sub.read("y", STRING)) == "t.toml:4: team.sub.y: is required (a string)"


def test_files_that_do_not_parse_or_read(tmp_path: Path) -> None:
    assert fails(lambda: toml_table("[a]\nx = = 1\n", "t.toml", FileError)).startswith(
        "t.toml:2: not valid TOML: "
    )
    assert fails(lambda: json_table('{"a":\n  }', "j.json", FileError)) == (
        "j.json:2: not valid JSON: Expecting value (column 3)"
    )
    assert fails(lambda: json_table("[1]", "j.json", FileError)) == (
        "j.json: must be a JSON object, got [1]"
    )
    json = json_table('{"a": {"b": [1, "x"]}}', "j.json", FileError)
    inner = json.table("a")
    assert inner is not None
    assert fails(lambda: inner.read("b", vector(2))) == (
        "j.json: a.b: must be a list of 2 numbers, got [1, 'x']"
    )
    latin = tmp_path / "latin.toml"
    latin.write_bytes("name = 'café'".encode("latin-1"))
    assert "not valid TOML: not UTF-8 text" in fails(
        lambda: read_text(latin, FileError, most=100, form="TOML")
    )
    assert fails(lambda: read_text(latin, FileError, most=4)).endswith("is over 4 bytes")
    assert "cannot read: " in fails(lambda: read_text(tmp_path / "no", FileError, most=10))


def test_matrix_rows_of_cells() -> None:
    table = Table({"g": [[0, 1], [1, 0]], "h": [[0, 1], [1]], "i": [[0, True]]}, Source("m"))
    assert matrix(table, "g", (0, 1), most=2) == [[0, 1], [1, 0]]
    assert fails(lambda: matrix(table, "g", (0, 1), most=1)).startswith("m: g: must be a list")
    assert fails(lambda: matrix(table, "h", (0, 1), most=9)) == (
        "m: h[1]: must be a row of 2 cells (as row 0), got 1"
    )
    assert fails(lambda: matrix(table, "i", (0, 1), most=9)) == (
        "m: i[0][1]: must be 0 or 1, got True"
    )


def test_every_file_error_is_a_file_error_and_a_config_error() -> None:
    for cls in (TeamFileError, WorldFileError, GridFileError, MazeFileError):
        assert issubclass(cls, FileError) and issubclass(cls, ConfigError)
        assert issubclass(cls, ValueError)
    error = WorldFileError("w.toml", "robot.mass", "must be a number, got 'x'", line=4)
    assert str(error) == "w.toml:4: robot.mass: must be a number, got 'x'"
    assert error.field == error.where == "robot.mass"
    assert str(FileError("f", "", "cannot read: gone")) == "f: cannot read: gone"
