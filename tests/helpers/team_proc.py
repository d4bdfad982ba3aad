"""A team member for the collectives' integration tests: hosts test programs.

``python -m tests.helpers.team_proc --name NAME``; team and zenoh settings from MOVER_*.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mover import MemberLost, RunTeam
from mover.testing import serve_programs


async def ties(robot: None, team: RunTeam, rounds: int, start: float, gap: float) -> list[str]:
    """OR rounds in which every member finishes at the same instant."""
    winners = []
    for k in range(rounds):

        async def op(k: int = k) -> str:
            await asyncio.sleep(max(0.0, start + k * gap - time.time()))
            return team.me

        outcome = await team.distributed_or(op)
        winners.append(outcome.winner)
    return winners


async def cleanup(robot: None, team: RunTeam, winner: str, marker_dir: str) -> str:
    """OR in which one member wins and the others must clean up."""
    marker = Path(marker_dir) / team.me

    async def op() -> str:
        if team.me == winner:
            await asyncio.sleep(0.3)
            return "the box"
        marker.write_text("started")
        try:
            await asyncio.sleep(3600)
            return "never"
        finally:
            marker.write_text("cleaned")  # the motors stop here

    outcome = await team.distributed_or(op)
    return f"{outcome.winner}:{outcome.result}"


async def and_wait(robot: None, team: RunTeam, slow: str) -> str:
    """AND in which ``slow`` never finishes (the test kills it)."""

    async def op() -> str:
        await asyncio.sleep(3600 if team.me == slow else 0.0)
        return team.me

    try:
        await team.distributed_and(op)
    except MemberLost as exc:
        return f"lost {sorted(exc.members)} at {time.time()}"
    return "completed"


async def and_outage(robot: None, team: RunTeam, hold: float) -> dict[str, str]:
    """AND whose operations end while the network is down."""

    async def op() -> str:
        await asyncio.sleep(hold)
        return team.me.upper()

    results: dict[str, str] = await team.distributed_and(op)
    return results


async def or_outage(robot: None, team: RunTeam, hold: float) -> str:
    """OR whose operations end while the network is down (the first by name finishes first)."""

    async def op() -> str:
        await asyncio.sleep(hold + 0.1 * sorted(team.members).index(team.me))
        return team.me

    outcome = await team.distributed_or(op)
    return str(outcome.winner)


async def divide(robot: None, team: RunTeam, by: int) -> float:
    """A program with a bug when ``by`` is 0."""
    return 1 / by


PROGRAMS: dict[str, Callable[..., Any]] = {
    "divide": divide,
    "ties": ties,
    "cleanup": cleanup,
    "and_wait": and_wait,
    "and_outage": and_outage,
    "or_outage": or_outage,
}


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--name", required=True)
    logging.basicConfig(level=logging.WARNING, format="%(name)s %(levelname)s %(message)s")
    asyncio.run(serve_programs(p.parse_args().name, PROGRAMS, timeout=10))
