"""Errors of the grid world's files, in mover's tree of file errors.

Exception tree::

    mover.ConfigError (a ValueError)
    └── mover.FileError    a file is wrong: .source, .line, .where, .problem
        ├── GridFileError  a grid file (text or JSON) that cannot be read
        └── MazeFileError  a maze file that cannot be read
"""

from __future__ import annotations

from mover import FileError


class GridFileError(FileError):
    """A grid file is malformed; the message names the file, the line or key, and the fault."""


class MazeFileError(FileError):
    """A maze file is unreadable or malformed; the message names the file, the key and the fault."""
