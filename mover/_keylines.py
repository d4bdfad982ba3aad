"""Where each key of a TOML file is written: the line of a table header or of a ``key =``.

:mod:`tomllib` gives values without positions, so a TOML file's errors (team and world files,
:mod:`mover._tables`) would otherwise name only a key. This reads the text once more, line by
line, and maps every key path (``("robots", 1, "count")``; an array of tables counts its
``[[...]]`` headers, and the array itself is at its first) to the line that wrote it. It
understands what those files use — headers, bare, quoted and dotted keys, comments, multi-line
strings and arrays — and falls back to the nearest enclosing key it knows,
so an odd construct costs precision (a nearby line), never an error.
"""

from __future__ import annotations

import re

Path = tuple[str | int, ...]

_KEY = re.compile(
    r"""\s*((?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*'))*)\s*="""
)
_HEADER = re.compile(r"\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(?:#.*)?$")


def _parts(dotted: str) -> list[str]:
    """``a."b.c".d`` -> ``["a", "b.c", "d"]``."""
    found = re.findall(r"""[A-Za-z0-9_-]+|"[^"]*"|'[^']*'""", dotted)
    return [p[1:-1] if p[:1] in "\"'" else p for p in found]


class KeyLines:
    """The line (1-based) of every key path of one TOML text."""

    def __init__(self, text: str) -> None:
        self._lines: dict[Path, int] = {}
        self._arrays: dict[tuple[str, ...], int] = {}  # array-of-tables path -> last index
        table: Path = ()
        in_string: str | None = None  # the closing quotes of a multi-line string under way
        depth = 0  # open brackets of a multi-line array under way
        for number, line in enumerate(text.splitlines(), start=1):
            if in_string is not None:
                if in_string in line:
                    in_string = None
                continue
            if depth > 0:
                depth = max(0, depth + _brackets(line))
                continue
            header = _HEADER.match(line)
            if header:
                names = _parts(header.group(2))
                if header.group(1) == "[[":
                    key = tuple(names)
                    self._arrays[key] = self._arrays.get(key, -1) + 1
                    table = (*self._resolve(names[:-1]), names[-1], self._arrays[key])
                    self._lines.setdefault(table[:-1], number)  # the array: its first header
                else:
                    table = self._resolve(names)
                self._lines.setdefault(table, number)
                continue
            written = _KEY.match(line)
            if not written:
                continue
            path = (*table, *_parts(written.group(1)))
            self._lines.setdefault(path, number)
            rest = line[written.end() :]
            for quotes in ('"""', "'''"):
                if rest.count(quotes) % 2 == 1:
                    in_string = quotes
            if in_string is None:
                depth = max(0, _brackets(rest))

    def _resolve(self, names: list[str]) -> Path:
        """A header's path, with the last index of every array of tables it passes through."""
        path: list[str | int] = []
        for i, name in enumerate(names):
            path.append(name)
            index = self._arrays.get(tuple(names[: i + 1]))
            if index is not None:
                path.append(index)
        return tuple(path)

    def line(self, path: Path) -> int | None:
        """The line of ``path``, else of its nearest enclosing key written in the text."""
        while path:
            if path in self._lines:
                return self._lines[path]
            path = path[:-1]
        return None


def _brackets(text: str) -> int:
    """Opened minus closed square brackets outside strings and comments (roughly)."""
    text = re.sub(r""""(?:\\.|[^"\\])*"|'[^']*'""", "", text).split("#", 1)[0]
    return text.count("[") - text.count("]")
