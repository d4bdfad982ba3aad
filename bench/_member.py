"""A team member for bench/collectives.py: hosts the benchmark programs."""

from __future__ import annotations

import argparse
import asyncio
import random
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mover import RunTeam
from mover.testing import serve_programs


async def bench_or(robot: None, team: RunTeam, rounds: int) -> list[list[Any]]:
    """OR rounds: member ``round % n`` finishes after 5 ms, the others would take seconds."""
    out = []
    for k in range(rounds):
        winner = team.members[k % len(team.members)]
        finished = [0.0]

        async def op(winner: str = winner, finished: list[float] = finished) -> str:
            await asyncio.sleep(0.005 if team.me == winner else 10.0)
            finished[0] = time.time()
            return team.me

        outcome = await team.distributed_or(op)
        out.append([finished[0], time.time(), outcome.winner, team.metrics[-1].messages])
    return out


async def bench_and(
    robot: None, team: RunTeam, rounds: int, designated: bool, seed: int
) -> list[list[Any]]:
    """AND rounds: every member finishes after a random 0-20 ms."""
    rng = random.Random(seed + team.members.index(team.me))
    out = []
    for _ in range(rounds):
        finished = [0.0]

        async def op(finished: list[float] = finished) -> str:
            await asyncio.sleep(rng.uniform(0.0, 0.02))
            finished[0] = time.time()
            return team.me

        results = await team.distributed_and(op, designated=designated)
        assert len(results) == len(team.members)
        out.append([finished[0], time.time(), team.metrics[-1].messages])
    return out


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--name", required=True)
    programs = {"bench_or": bench_or, "bench_and": bench_and}
    asyncio.run(serve_programs(p.parse_args().name, programs))
