"""`mover topics`: the broadcast topics heard on a team, with their rates.

It joins as an observer (not a member: programs and ``mover ps`` never see it) and listens on
every broadcast key of the team (``mover/<team>/bc/**``) for ``--seconds``, counting frames and
bytes per topic. It opens nothing: the counts need only the key and the size, which any node on
the network sees (docs: what an outsider still sees), so a topic's messages stay sealed. A frame
is one sealed envelope: broadcasts a member makes in one loop turn leave as one frame per topic,
so a rate is of frames, not of messages. The subscriber is a zenoh FIFO channel polled from the
loop every ``POLL`` seconds, so no zenoh thread calls into asyncio here.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import secrets
import sys
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import zenoh

from .. import _keys
from .._config import NodeConfig, TeamCredentials
from . import add_command, add_team_arguments, bounded, team_from_args

if TYPE_CHECKING:
    Sub = argparse._SubParsersAction[argparse.ArgumentParser]

__all__ = ["TopicRate", "rates", "register"]

POLL = 0.05  # seconds between two reads of the subscriber's queue
QUEUE = 10_000  # frames the queue holds between two reads; more are dropped by zenoh
MAX_SECONDS = 3600.0


@dataclass(frozen=True)
class TopicRate:
    """What was heard on one topic: frames, their rate (per second) and mean size (bytes)."""

    topic: str
    frames: int
    rate: float
    mean_bytes: float


def rates(counts: dict[str, tuple[int, int]], seconds: float) -> list[TopicRate]:
    """``{topic: (frames, bytes)}`` heard over ``seconds`` as rows, busiest first."""
    rows = [
        TopicRate(topic, n, n / seconds if seconds > 0 else 0.0, size / n if n else 0.0)
        for topic, (n, size) in counts.items()
    ]
    return sorted(rows, key=lambda r: (-r.frames, r.topic))


def register(sub: Sub) -> None:
    """Add ``mover topics``."""
    p = add_command(
        sub, "topics", run_topics, "the broadcast topics heard on the team, with their rates"
    )
    p.add_argument(
        "--seconds",
        type=bounded(float, 0.0, MAX_SECONDS, above=True),
        default=3.0,
        metavar="S",
        help="how long to listen (default 3)",
    )
    p.add_argument("--json", action="store_true", help="one JSON object per topic")
    add_team_arguments(p)


def run_topics(args: argparse.Namespace) -> int:
    """Listen to every broadcast of the team for --seconds and print each topic heard: frames,
    frames per second and mean size. Counts are of sealed frames (a member's broadcasts of one
    loop turn leave as one frame per topic); nothing is decoded (`mover echo TOPIC` decodes
    one). A lock-step world sends nothing while no run drives it."""
    team, config = team_from_args(args)
    return asyncio.run(_topics(team, config, args.seconds, args.json))


async def _topics(team: TeamCredentials, config: NodeConfig, seconds: float, as_json: bool) -> int:
    from .._node import Node

    prefix = _keys.broadcast(team.name, "")
    counts: dict[str, tuple[int, int]] = {}
    async with Node(
        f"topics-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        print(f"mover topics: listening to team {team.name!r} for {seconds:g} s", file=sys.stderr)
        subscriber = node.zenoh_session.declare_subscriber(
            _keys.broadcast(team.name, "**"), zenoh.handlers.FifoChannel(QUEUE)
        )
        start = time.monotonic()
        end = start + seconds
        try:
            while True:
                while (sample := subscriber.try_recv()) is not None:
                    topic = str(sample.key_expr).removeprefix(prefix)
                    n, size = counts.get(topic, (0, 0))
                    counts[topic] = (n + 1, size + len(sample.payload.to_bytes()))
                if time.monotonic() >= end:
                    break
                await asyncio.sleep(POLL)
        finally:
            subscriber.undeclare()
        elapsed = time.monotonic() - start
    rows = rates(counts, elapsed)
    if as_json:
        for r in rows:
            row = {"topic": r.topic, "frames": r.frames, "rate": round(r.rate, 2)}
            print(json.dumps({**row, "mean_bytes": round(r.mean_bytes)}))
        return 0
    if not rows:
        print(
            f"no broadcast heard in {elapsed:.1f} s (is the team up, and MOVER_CONNECT one of"
            " its endpoints? an idle lock-step world is silent)"
        )
        return 0
    width = max(len("topic"), *(len(r.topic) for r in rows))
    print(f"{'topic':<{width}}  {'frames':>7}  {'per s':>8}  {'bytes':>7}")
    for r in rows:
        print(f"{r.topic:<{width}}  {r.frames:>7}  {r.rate:>8.1f}  {r.mean_bytes:>7.0f}")
    return 0
