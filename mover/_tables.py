"""One validating reader for the tables of files: team, world, grid and maze files.

It owns reading such a file (bounded in size, UTF-8, TOML or JSON) and reading its decoded
tables key by key, refusing what does not fit with one wording: the file, the line (in TOML,
the line that writes the key, found by :class:`~mover._keylines.KeyLines`; JSON keeps none),
the key, what was expected and, for a misspelt key, "did you mean"::

    teams/a.toml:8: robots[1].count: must be from 1 to 200, got 1000
    worlds/b.toml:4: robot.radious: unknown key (did you mean 'radius'?); known: pose, radius, ...

A value is read through a :class:`Kind` (:func:`number`, :func:`integer`, :func:`vector`,
:func:`string`, :data:`BOOLEAN`, :data:`NAME`, :data:`MAPPING`), and every number and count is
bounded where it is read. Why one reader: team files and world files had one each, with other
words for the same mistakes; a reader's errors are :class:`~mover._exceptions.FileError`
subclasses of its caller's choosing. What it costs: nothing beyond the decoding on a valid file;
a TOML file's text is scanned once more for the line only when an error is raised.
"""

from __future__ import annotations

import difflib
import enum
import json
import math
import re
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeGuard, TypeVar

from ._exceptions import FileError
from ._keylines import KeyLines
from ._keylines import Path as KeyPath
from ._keys import check_name

T = TypeVar("T")

MAX_NUMBER = 1e6
"""The largest magnitude of a number read where its reader names no other bound."""


class _Required(enum.Enum):
    REQUIRED = enum.auto()


REQUIRED = _Required.REQUIRED
"""The default of :meth:`Table.read` for a key the table must have."""


class Wrong(Exception):
    """A value does not fit its kind; the message says what was expected (``must be ...``)."""


@dataclass(frozen=True)
class Kind(Generic[T]):
    """What a value must be: ``expected`` in words, and ``check``, which returns the value read
    or raises :class:`Wrong`."""

    expected: str
    check: Callable[[object], T]


@dataclass(frozen=True)
class Source:
    """One file being read: its name in messages, its error class, and its TOML text (whose
    keys' lines are looked up only when an error needs one: a valid file costs no second pass)."""

    name: str
    error: type[FileError] = FileError
    toml: str | None = None

    def fail(self, path: KeyPath, problem: str) -> FileError:
        """The error for ``problem`` at the key ``path`` (its line, if the file keeps lines)."""
        line = KeyLines(self.toml).line(path) if self.toml is not None else None
        return self.error(self.name, dotted(path), problem, line=line)


class Table:
    """A decoded table read key by key; :meth:`only` or :meth:`done` refuses unknown keys."""

    def __init__(self, data: object, source: Source, path: KeyPath = ()) -> None:
        if not isinstance(data, dict):
            raise source.fail(path, f"must be a table, got {shown(data)}")
        self.data: dict[str, Any] = data
        self.source, self.path = source, path
        self.seen: dict[str, None] = {}  # the keys asked for, in order: the known ones

    def fail(self, key: str | int | KeyPath, problem: str) -> FileError:
        """The error for ``problem`` at ``key`` (a key, an index, or a path) of this table."""
        return self.source.fail((*self.path, *(key if isinstance(key, tuple) else (key,))), problem)

    def has(self, key: str) -> bool:
        """Whether the table writes ``key``."""
        return key in self.data

    def get(self, key: str) -> object:
        """The raw value of ``key`` (None if absent), which is known from now on."""
        self.seen[key] = None
        return self.data.get(key)

    def read(self, key: str, kind: Kind[T], default: T | _Required = REQUIRED) -> T:
        """The value of ``key`` as ``kind``; ``default`` if absent, refused if that is required."""
        value = self.get(key)
        if value is not None:
            return self.check(key, value, kind)
        if isinstance(default, _Required):
            raise self.fail(key, f"is required ({kind.expected})")
        return default

    def option(self, key: str, kind: Kind[T]) -> T | None:
        """The value of ``key`` as ``kind``, or None if absent."""
        value = self.get(key)
        return None if value is None else self.check(key, value, kind)

    def check(self, key: str | int | KeyPath, value: object, kind: Kind[T]) -> T:
        """``value`` (found at ``key``) as ``kind``."""
        try:
            return kind.check(value)
        except Wrong as exc:
            raise self.fail(key, str(exc)) from None

    def table(self, key: str) -> Table | None:
        """The sub-table ``key``, or None if absent."""
        value = self.get(key)
        return None if value is None else Table(value, self.source, (*self.path, key))

    def tables(self, key: str, *, most: int) -> list[Table]:
        """The array of tables ``key`` (``[[key]]``), at most ``most`` of them; [] if absent."""
        value = self.get(key)
        if value is None:
            return []
        if not isinstance(value, list):
            raise self.fail(key, f"must be an array of tables ([[{key}]]), got {shown(value)}")
        if len(value) > most:
            raise self.fail(key, f"must hold at most {most} tables, got {len(value)}")
        return [Table(v, self.source, (*self.path, key, i)) for i, v in enumerate(value)]

    def only(self, known: Iterable[str], *, kind: str | None = None) -> None:
        """Refuse any key but ``known`` (``kind`` says what this table is, for the message)."""
        known = tuple(known)
        for key in self.data:
            if key not in known:
                raise self.fail(key, unknown(key, known, kind))

    def done(self) -> None:
        """Refuse any key not asked for (a typo must not pass silently)."""
        self.only(self.seen)


def unknown(key: str, known: Iterable[str], kind: str | None = None) -> str:
    """The one wording of an unknown key: where, a close known key, and the known keys."""
    known = list(known)
    what = f" in {kind}" if kind else ""
    return f"unknown key{what}{hint(key, known)}; known: {', '.join(known) or 'none'}"


def hint(word: str, known: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the known word closest to ``word``, else ""."""
    close = difflib.get_close_matches(str(word), list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def dotted(path: KeyPath) -> str:
    """``("robots", 1, "count")`` -> ``robots[1].count``."""
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path).lstrip(".")


def shown(value: object) -> str:
    """A value as a message shows it: a table by its kind, anything else by a short repr."""
    if isinstance(value, dict):
        return "a table"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _span(low: float | None, high: float, strict: bool) -> str:
    if low is None:
        return f"from {_num(-high)} to {_num(high)}"
    if strict:
        return f"> {_num(low)} and at most {_num(high)}"
    return f"from {_num(low)} to {_num(high)}"


def _num(x: float) -> str:
    """A bound in words: ``1000000`` rather than ``1e+06``."""
    return str(int(x)) if x.is_integer() and abs(x) < 1e16 else f"{x:g}"


def _real(value: object) -> TypeGuard[int | float]:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def number(
    *, low: float | None = 0.0, high: float = MAX_NUMBER, strict: bool = True
) -> Kind[float]:
    """A finite number above ``low`` (at or above it unless ``strict``; None: ``-high``), at most
    ``high``."""
    span = _span(low, high, strict)

    def check(value: object) -> float:
        if not _real(value):
            raise Wrong(f"must be a number, got {shown(value)}")
        v = float(value)
        below = v < -high if low is None else (v <= low if strict else v < low)
        if below or v > high:
            raise Wrong(f"must be {span}, got {value!r}")
        return v

    return Kind("a number", check)


def integer(*, low: int = 0, high: int) -> Kind[int]:
    """A whole number from ``low`` to ``high``."""

    def check(value: object) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise Wrong(f"must be an integer, got {shown(value)}")
        if not low <= value <= high:
            raise Wrong(f"must be from {low} to {high}, got {value}")
        return value

    return Kind("an integer", check)


def vector(
    n: int, *, low: float | None = None, high: float = MAX_NUMBER, strict: bool = True
) -> Kind[tuple[float, ...]]:
    """A list of ``n`` numbers, each within the bounds of :func:`number`."""
    each = number(low=low, high=high, strict=strict)
    expected = f"a list of {n} numbers"

    def check(value: object) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != n or not all(map(_real, value)):
            raise Wrong(f"must be {expected}, got {shown(value)}")
        try:
            return tuple(each.check(v) for v in value)
        except Wrong:
            raise Wrong(
                f"must be {expected}, each {_span(low, high, strict)}, got {shown(value)}"
            ) from None

    return Kind(expected, check)


def pair(
    *, low: float | None = None, high: float = MAX_NUMBER, strict: bool = True
) -> Kind[tuple[float, float]]:
    """:func:`vector` of two numbers (a point, a size)."""
    two = vector(2, low=low, high=high, strict=strict)

    def check(value: object) -> tuple[float, float]:
        x, y = two.check(value)
        return (x, y)

    return Kind(two.expected, check)


def string(choices: tuple[str, ...] = ()) -> Kind[str]:
    """A string; one of ``choices`` if any are given."""
    expected = "a string"
    if choices:
        expected = ", ".join(repr(c) for c in choices[:-1]) + f" or {choices[-1]!r}"
        expected = expected.removeprefix(" or ")

    def check(value: object) -> str:
        if not isinstance(value, str) or (choices and value not in choices):
            raise Wrong(f"must be {expected}, got {shown(value)}")
        return value

    return Kind(expected, check)


def _boolean(value: object) -> bool:
    if not isinstance(value, bool):
        raise Wrong(f"must be true or false, got {shown(value)}")
    return value


def _name(value: object) -> str:
    if not isinstance(value, str):
        raise Wrong(f"must be a name (a string), got {shown(value)}")
    try:
        return check_name("member", value)
    except ValueError as exc:
        raise Wrong(str(exc)) from None


def _mapping(value: object) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise Wrong(f"must be a table, got {shown(value)}")
    return value


BOOLEAN = Kind("true or false", _boolean)
"""``true`` or ``false``."""
NAME = Kind("a name", _name)
"""A member name (a robot, world or eye-bot process's name in the team)."""
MAPPING = Kind("a table", _mapping)
"""A table taken whole, its keys unchecked here (they are a robot's settings, a layout...)."""
STRING = string()
"""Any string."""


# -- files -------------------------------------------------------------------------------------


def read_text(path: Path, error: type[FileError], *, most: int, form: str = "") -> str:
    """The text of the file at ``path``, at most ``most`` bytes of UTF-8; ``form`` ("TOML",
    "JSON") says what it should be, for the message when it is not UTF-8."""
    source = str(path)
    try:
        if path.stat().st_size > most:
            limit = f"{most / 2**20:g} MiB" if most >= 2**20 else f"{most} bytes"
            raise error(source, "", f"is over {limit}")
        raw = path.read_bytes()
    except OSError as exc:
        raise error(source, "", f"cannot read: {exc.strerror or exc}") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        what = f"not valid {form}: " if form else ""
        raise error(source, "", f"{what}not UTF-8 text ({exc.reason})") from None


def toml_table(text: str, source: str, error: type[FileError]) -> Table:
    """The root table of the TOML ``text``, its errors naming the lines of their keys."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        found = re.search(r"at line (\d+)", str(exc))
        line = int(found.group(1)) if found else None
        raise error(source, "", f"not valid TOML: {exc}", line=line) from None
    except RecursionError:
        raise error(source, "", "not valid TOML: nested too deeply") from None
    return Table(data, Source(source, error, text))


def json_table(text: str, source: str, error: type[FileError]) -> Table:
    """The root table (object) of the JSON ``text``."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        problem = f"not valid JSON: {exc.msg} (column {exc.colno})"
        raise error(source, "", problem, line=exc.lineno) from None
    except RecursionError:
        raise error(source, "", "not valid JSON: nested too deeply") from None
    if not isinstance(data, dict):
        raise error(source, "", f"must be a JSON object, got {shown(data)}")
    return Table(data, Source(source, error))


def matrix(t: Table, key: str, cells: tuple[int, ...], *, most: int) -> list[list[int]]:
    """The rows of ``key``: a non-empty list of at most ``most`` rows of at most ``most``
    integers each, all as long as the first, each one of ``cells``."""
    rows = t.get(key)
    if rows is None:
        raise t.fail(key, "is required (a list of rows)")
    if not isinstance(rows, list) or not rows or len(rows) > most:
        raise t.fail(key, f"must be a list of 1 to {most} rows, got {shown(rows)}")
    allowed = " or ".join(str(c) for c in cells)
    first = rows[0]
    width = len(first) if isinstance(first, list) and 0 < len(first) <= most else 0
    for r, row in enumerate(rows):
        n = len(row) if isinstance(row, list) else shown(row)
        if not width:
            raise t.fail((key, r), f"must be a row of 1 to {most} cells, got {n}")
        if not isinstance(row, list) or len(row) != width:
            raise t.fail((key, r), f"must be a row of {width} cells (as row 0), got {n}")
        for c, v in enumerate(row):
            if isinstance(v, bool) or not isinstance(v, int) or v not in cells:
                raise t.fail((key, r, c), f"must be {allowed}, got {shown(v)}")
    return rows
