"""Range-limited broadcast at scale: does a team's cost grow with the neighbourhood or the team?

    python bench/radio.py [--sizes 25,50,100,200] [--density 0.25] [--range 3]
                          [--rate 1] [--seconds 8]

N members (N in ``--sizes``) random-walk at 0.5 m/s in a square arena holding ``--density``
robots per m², and each broadcasts ``--rate`` times a second on one topic with range
``--range`` m, hearing the others' broadcasts. Every member is a full mover node with its own
zenoh session, a client of one ``mover router`` process; the nodes run **in one process**, one
node per robot (two cores cannot hold 200 robot processes and their start-up in a reasonable
time). Each size is run twice in the same run: with broadcasts under spatial cells (today's
code) and flat (``cells = False``: one key per topic, every receiver opens every frame — the code
path before cells). Over a window of ``--seconds`` after a warm-up:

- ``radio_cpu_N`` / ``radio_cpu_N_flat``: CPU-s per s of the whole team (the members' process and
  the router, from /proc);
- ``radio_delivered_N`` / ``radio_delivered_N_flat``: messages delivered per s per robot (the
  same in both modes if cells lose nothing);
- ``radio_cpu_growth_200_vs_50`` (target <= 5; N² would be 16) and
  ``radio_cpu_growth_200_vs_50_flat``, from the largest and second size given.

The last line is one JSON object of the figures.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import os
import random
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mover import FixedLocator, Node, NodeConfig, TeamCredentials  # noqa: E402
from mover._config import free_port  # noqa: E402

TICK = os.sysconf("SC_CLK_TCK")
SPEED = 0.5  # m/s
STEP = 0.1  # s between moves


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU time so far of the processes ``pids`` (all their threads)."""
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])
    return total / TICK


async def run(size: int, cells: bool, args: argparse.Namespace) -> dict[str, float]:
    """One team of ``size``: CPU-s/s of the team and messages delivered per s per robot."""
    side = math.sqrt(size / args.density)
    rng = random.Random(size)
    team, port = TeamCredentials.generate("radio"), free_port()
    seed = f"tcp/127.0.0.1:{port}"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    router = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", "router", "--listen", seed,
        env=env, cwd=ROOT, stdout=asyncio.subprocess.PIPE,
    )  # fmt: skip
    try:
        assert router.stdout is not None
        await asyncio.wait_for(router.stdout.readline(), 30)
        config = NodeConfig(mode="client", listen=(), connect=(seed,))
        names = [f"r{i:03d}" for i in range(size)]
        async with contextlib.AsyncExitStack() as stack:
            nodes: list[Node] = []
            places: list[FixedLocator] = []
            for name in names:
                place = FixedLocator(rng.uniform(0, side), rng.uniform(0, side), 0.0)
                node = Node(name, team, kind="bench", config=config, locator=place)
                node._pubsub.cells = cells
                nodes.append(await stack.enter_async_context(node))
                places.append(place)
            await asyncio.gather(*(n.membership.wait_for(names, timeout=120) for n in nodes))
            subs = [n.subscribe("beacon") for n in nodes]
            headings = [rng.uniform(0, 2 * math.pi) for _ in nodes]
            phase = [rng.randrange(round(1 / (args.rate * STEP))) for _ in nodes]

            async def tick(k: int) -> int:
                for i, place in enumerate(places):  # a random walk, bouncing off the walls
                    headings[i] += rng.gauss(0.0, 0.3)
                    x = place.x + SPEED * STEP * math.cos(headings[i])
                    y = place.y + SPEED * STEP * math.sin(headings[i])
                    if not (0 <= x <= side and 0 <= y <= side):
                        headings[i] += math.pi
                    else:
                        place.x, place.y = x, y
                    if k % round(1 / (args.rate * STEP)) == phase[i]:
                        nodes[i].broadcast_nowait("beacon", k, range=args.range)
                await asyncio.sleep(STEP)
                return sum(len(s.drain()) for s in subs)

            for k in range(round(3.0 / STEP)):  # warm-up: grace over, cells declared
                await tick(k)
            pids = [os.getpid(), router.pid]
            before, t0, got = cpu_seconds(pids), time.monotonic(), 0
            for k in range(round(args.seconds / STEP)):
                got += await tick(k)
            wall = time.monotonic() - t0
            cpu = (cpu_seconds(pids) - before) / wall
            for s in subs:
                s.close()
    finally:
        router.kill()
        await router.wait()
    delivered = got / wall / size
    label = "cells" if cells else "flat"
    print(
        f"{size:4d} robots, {label:5}: {cpu:.3f} CPU-s/s, {delivered:.2f} msgs/s a robot",
        flush=True,
    )
    return {"cpu": cpu, "delivered": delivered}


async def main(args: argparse.Namespace) -> dict[str, Any]:
    sizes = [int(s) for s in args.sizes.split(",")]
    out: dict[str, Any] = {
        "radio_setup": "one process, one node per robot, clients of one router process",
        "radio_density": args.density,
        "radio_range": args.range,
        "radio_rate": args.rate,
    }
    for size in sizes:
        for cells in (True, False):
            got = await run(size, cells, args)
            tail = "" if cells else "_flat"
            out[f"radio_cpu_{size}{tail}"] = round(got["cpu"], 4)
            out[f"radio_delivered_{size}{tail}"] = round(got["delivered"], 3)
    if len(sizes) >= 2:
        big, small = sizes[-1], sizes[1] if len(sizes) > 2 else sizes[0]
        for tail in ("", "_flat"):
            growth = out[f"radio_cpu_{big}{tail}"] / out[f"radio_cpu_{small}{tail}"]
            out[f"radio_cpu_growth_{big}_vs_{small}{tail}"] = round(growth, 2)
    return out


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="25,50,100,200", help="team sizes (default 25,50,100,200)")
    p.add_argument("--density", type=float, default=0.25, help="robots per m² (default 0.25)")
    p.add_argument("--range", type=float, default=3.0, help="broadcast range, m (default 3)")
    p.add_argument("--rate", type=float, default=1.0, help="broadcasts per s a robot (default 1)")
    p.add_argument("--seconds", type=float, default=8.0, help="measured window (default 8)")
    print(json.dumps(asyncio.run(main(p.parse_args()))))
