"""A team member for tests/mover/test_run_control.py: hosts programs that hold, pause and draw.

``python -m tests.mover._run_member NAME``; team and zenoh settings from MOVER_*.
"""

from __future__ import annotations

import asyncio
import logging
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mover import RunTeam
from mover.testing import serve_programs


async def hold(robot: None, team: RunTeam, marker_dir: str) -> str:
    """Run until cancelled; the ``finally`` block leaves a mark (``<member>`` = "cleaned")."""
    marker = Path(marker_dir) / f"{team.run}.{team.me}"
    marker.write_text("started")
    await team.report("holding", step=1)
    try:
        await asyncio.sleep(3600)
        return "never"
    finally:
        marker.write_text("cleaned")


async def pause(robot: None, team: RunTeam, seconds: float) -> str:
    """Report, wait ``seconds``, report again, end with this member's name."""
    await team.report("pausing")
    await asyncio.sleep(seconds)
    await team.report("waking", after=seconds)
    return team.me


async def draw(robot: None, team: RunTeam, n: int) -> dict[str, Any]:
    """The run's seed and ``n`` draws from ``team.rng("x")``."""
    rng = team.rng("x")
    return {"seed": team.seed, "draws": [rng.random() for _ in range(n)]}


PROGRAMS: dict[str, Callable[..., Any]] = {"hold": hold, "pause": pause, "draw": draw}


if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, format="%(name)s %(levelname)s %(message)s")
    asyncio.run(serve_programs(sys.argv[1], PROGRAMS, timeout=20))
