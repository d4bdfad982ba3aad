"""Errors of the grid world.

Exception tree::

    ValueError
    └── GridFileError      a grid file that cannot be read (names file, line/field, problem)
"""

from __future__ import annotations


class GridFileError(ValueError):
    """A grid file is malformed; the message names the file, the line or field, and the fault."""

    def __init__(self, source: str, where: str, problem: str) -> None:
        self.source = source
        self.where = where
        self.problem = problem
        super().__init__(f"{source}: {where}: {problem}")
