"""A team member for bench/collectives.py: hosts the benchmark programs."""

from __future__ import annotations

import argparse
import asyncio
import random
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import zenoh

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


async def bench_raw_or(robot: None, team: RunTeam, rounds: int) -> list[list[Any]]:
    """The floor of an OR step, without mover: the winner's one zenoh put to every member, and
    each member cancelling its operation when the put arrives (handed into its loop). The
    rounds are kept in step by an untimed mover AND between them. The put is as reliable as
    mover's own OR announcement (congestion control BLOCK): zenoh's default, DROP, lost it
    under load once, and the members disagreed on the winner."""
    session = team.node.zenoh_session
    loop = asyncio.get_running_loop()
    got: asyncio.Queue[tuple[str, str]] = asyncio.Queue()

    def on_sample(sample: Any) -> None:
        item = (str(sample.key_expr), sample.payload.to_bytes().decode())
        loop.call_soon_threadsafe(got.put_nowait, item)

    sub = session.declare_subscriber("bench/raw-or/**", on_sample)
    out = []
    try:
        await asyncio.sleep(0.5)  # the subscriptions reach every member
        for k in range(rounds):
            await team.distributed_and(lambda: asyncio.sleep(0))  # untimed: a barrier
            winner = team.members[k % len(team.members)]
            finished = [0.0]

            async def op(
                winner: str = winner, finished: list[float] = finished, k: int = k
            ) -> None:
                await asyncio.sleep(0.005 if team.me == winner else 10.0)
                finished[0] = time.time()
                session.put(
                    f"bench/raw-or/{k}",
                    team.me.encode(),
                    congestion_control=zenoh.CongestionControl.BLOCK,
                )

            task = asyncio.ensure_future(op())
            while True:
                key, who = await asyncio.wait_for(got.get(), 20)
                if key == f"bench/raw-or/{k}":
                    break
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)
            out.append([finished[0], time.time(), who, 1])
    finally:
        sub.undeclare()
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
    programs: dict[str, Callable[..., Any]] = {
        "bench_or": bench_or,
        "bench_raw_or": bench_raw_or,
        "bench_and": bench_and,
    }
    asyncio.run(serve_programs(p.parse_args().name, programs))
