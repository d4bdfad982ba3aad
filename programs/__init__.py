"""Coordination programs: they read like the papers and use only ``mover`` and ``robots``.

A program is ``async def program(robot, team, **args)``: every member of the team runs it,
started by name with data arguments. The names are the ``mover.programs`` entry points
(pyproject.toml), the one list of them; :func:`installed` loads them as a robot process does.
The experiment runners that drive these programs' behaviours in-process live in
``experiments/``, which may import the simulated hardware; nothing here does.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["installed"]


def installed() -> dict[str, Callable[..., Any]]:
    """The installed programs by the name they are started by (``mover.programs``), loaded."""
    from robots.process import installed_programs

    found = installed_programs()  # loads each one when asked: ask for every one
    return {name: fn for name in found if (fn := found.get(name)) is not None}
