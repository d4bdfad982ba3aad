"""Coordination programs (they read like the papers) and experiment runners.

``PROGRAMS`` maps the name a program is started by to the installed coroutine function that
every member of the team runs (``async def program(robot, team, **args)``).
"""

from .follow_trainer import follow_trainer
from .search_and_rescue import search_and_rescue

PROGRAMS = {
    "search_and_rescue": search_and_rescue,
    "follow_trainer": follow_trainer,
}

__all__ = ["PROGRAMS", "follow_trainer", "search_and_rescue"]
