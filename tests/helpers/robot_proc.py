"""A robot process for mover's integration tests: a node with test procedures.

Run as ``python -m tests.helpers.robot_proc --name NAME [--x X --y Y --heading H]``; team and
zenoh settings come from the MOVER_* environment. Prints ``READY`` once it is a member.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
import sys
import time
from pathlib import Path
from typing import Any

from mover import FixedLocator, Node, NodeConfig, TeamCredentials
from mover._collective import Collectives

TOPICS = ("news", "chatter", "probe")


async def main(args: argparse.Namespace) -> None:
    team = TeamCredentials.from_env()
    state = {"bumps": 0}
    heard: dict[str, list[list[Any]]] = {t: [] for t in TOPICS}
    locator = FixedLocator(args.x, args.y, args.heading)
    async with Node(
        args.name,
        team,
        kind=args.kind,
        config=NodeConfig.from_env(),
        locator=locator,
        max_size=args.max_size,
    ) as node:

        async def add(x: int, y: int) -> int:
            return x + y

        def boom(message: str) -> None:
            raise ValueError(message)

        async def sleep(seconds: float) -> str:
            await asyncio.sleep(seconds)
            return "slept"

        async def hold(marker: str) -> None:
            Path(marker).write_text("started")
            try:
                await asyncio.Event().wait()
            finally:
                Path(marker).write_text("cleaned")

        def bump() -> int:
            state["bumps"] += 1
            return state["bumps"]

        def bumps() -> int:
            return state["bumps"]

        def send(topic: str, data: Any, range: float | None = None) -> None:
            node.broadcast_nowait(topic, data, range=range)

        def heard_on(topic: str) -> list[list[Any]]:
            return heard[topic]

        async def call_other(robot: str, procedure: str, args: list[Any]) -> Any:
            return await node.call(robot, procedure, *args, timeout=5.0)

        def echo(data: bytes) -> int:
            return len(data)

        def block(seconds: float) -> None:
            time.sleep(seconds)  # holds the loop up, as a busy or stuck program would

        def rss_kb() -> int:
            status = Path("/proc/self/status").read_text()
            return int(next(x for x in status.splitlines() if x.startswith("VmRSS")).split()[1])

        def flooded() -> int:
            return counts["flood"]

        for fn in (add, boom, sleep, hold, bump, bumps, send, call_other, echo, block, rss_kb):
            node.export(fn)
        node.export(flooded)
        node.export(heard_on, "heard")

        async def listen(topic: str) -> None:
            async for m in node.subscribe(topic):
                heard[topic].append([m.sender, m.data, m.distance, m.bearing])

        async def count(topic: str) -> None:  # a busy topic: counted, not kept
            async for _ in node.subscribe(topic, maxlen=1000):
                counts[topic] += 1

        counts = {"flood": 0}
        listeners = [asyncio.create_task(listen(t)) for t in TOPICS]
        listeners.append(asyncio.create_task(count("flood")))
        collectives = Collectives(node)  # its listener of OR decisions, for the fuzz tests

        def listening() -> bool:
            """Whether every listener of this process is still alive."""
            return not collectives._listener.done() and not any(t.done() for t in listeners)

        node.export(listening)
        await node.membership.wait_for({node.name}, timeout=10)
        print("READY", os.getpid(), flush=True)
        try:
            await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)
        finally:
            for task in listeners:
                task.cancel()


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--name", required=True)
    p.add_argument("--kind", default="robot")
    p.add_argument("--x", type=float, default=0.0)
    p.add_argument("--y", type=float, default=0.0)
    p.add_argument("--heading", type=float, default=0.0)
    p.add_argument("--max-size", type=int, default=4 * 1024 * 1024)
    logging.basicConfig(level=logging.INFO, format="%(name)s %(levelname)s %(message)s")
    asyncio.run(main(p.parse_args()))
