"""Range-limited broadcast at scale: does a team's cost grow with the neighbourhood or the team?

    python bench/radio.py [--sizes 25,50,100,200] [--density 0.25] [--range 3]
                          [--rate 1] [--seconds 8]

N members (N in ``--sizes``) random-walk at 0.5 m/s in a square arena holding ``--density``
robots per m², and each broadcasts ``--rate`` times a second on one topic with range
``--range`` m, hearing the others' broadcasts. Every member is a full mover node with its own
zenoh session, a client of one ``mover router`` process; the nodes run in ``--workers``
processes (default 4), several nodes per process, one node per robot (two cores cannot start
200 robot processes in a reasonable time, and one process cannot hold 200 nodes' membership
handshakes). Each size is run twice in the same run: with broadcasts under spatial cells (today's
code) and flat (``cells = False``: one key per topic, every receiver opens every frame — the code
path before cells). Over a window of ``--seconds`` after a warm-up:

- ``radio_cpu_N`` / ``radio_cpu_N_flat``: CPU-s per s of the whole team (the workers and the
  router, from /proc);
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
WARM_UP = 3.0  # s of walking and broadcasting before the window: the grace over, cells declared


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU time so far of the processes ``pids`` (all their threads)."""
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])
    return total / TICK


async def worker(args: argparse.Namespace) -> None:
    """A worker process: the nodes ``args.names`` of a team of ``args.size``; on ``run T0 T1``
    (CLOCK_MONOTONIC, machine-wide) they walk and broadcast until T1, and it prints how many
    messages they were delivered from T0 to T1."""
    names = args.names.split(",")
    team = [f"r{i:03d}" for i in range(args.size)]
    rng = random.Random(names[0])
    side = math.sqrt(args.size / args.density)
    config = NodeConfig.from_env()
    async with contextlib.AsyncExitStack() as stack:
        nodes: list[Node] = []
        places: list[FixedLocator] = []
        for name in names:
            place = FixedLocator(rng.uniform(0, side), rng.uniform(0, side), 0.0)
            node = Node(
                name, TeamCredentials.from_env(), kind="bench", config=config, locator=place
            )
            node._pubsub.cells = args.cells == "on"
            nodes.append(await stack.enter_async_context(node))
            places.append(place)
        await asyncio.gather(*(n.membership.wait_for(team, timeout=600) for n in nodes))
        subs = [n.subscribe("beacon") for n in nodes]
        headings = [rng.uniform(0, 2 * math.pi) for _ in nodes]
        every = round(1 / (args.rate * STEP))
        phase = [rng.randrange(every) for _ in nodes]
        print("READY", flush=True)
        loop = asyncio.get_running_loop()
        line = (await loop.run_in_executor(None, sys.stdin.readline)).split()
        t0, t1 = float(line[1]), float(line[2])
        got, k = 0, 0
        while (now := time.monotonic()) < t1:
            for i, place in enumerate(places):  # a random walk, bouncing off the walls
                headings[i] += rng.gauss(0.0, 0.3)
                x = place.x + SPEED * STEP * math.cos(headings[i])
                y = place.y + SPEED * STEP * math.sin(headings[i])
                if not (0 <= x <= side and 0 <= y <= side):
                    headings[i] += math.pi
                else:
                    place.x, place.y = x, y
                if k % every == phase[i]:
                    nodes[i].broadcast_nowait("beacon", k, range=args.range)
            k += 1
            await asyncio.sleep(STEP)
            heard = sum(len(s.drain()) for s in subs)
            if now >= t0:
                got += heard
        print(json.dumps({"got": got}), flush=True)
        for s in subs:
            s.close()


async def run(size: int, cells: bool, args: argparse.Namespace) -> dict[str, float]:
    """One team of ``size``: CPU-s/s of the team and messages delivered per s per robot."""
    team, port = TeamCredentials.generate("radio"), free_port()
    seed = f"tcp/127.0.0.1:{port}"
    env = dict(os.environ, PYTHONPATH=str(ROOT), **team.env())
    env.update(NodeConfig(mode="client", listen=(), connect=(seed,)).env())
    procs: list[asyncio.subprocess.Process] = []

    async def spawn(*argv: str) -> asyncio.subprocess.Process:
        proc = await asyncio.create_subprocess_exec(
            *argv, env=env, cwd=ROOT, stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
        )  # fmt: skip
        procs.append(proc)
        return proc

    async def line(proc: asyncio.subprocess.Process) -> str:
        assert proc.stdout is not None
        text = (await proc.stdout.readline()).decode()
        if not text:
            raise RuntimeError(f"a worker exited (status {await proc.wait()})")
        return text

    try:
        router = await spawn(sys.executable, "-m", "mover", "router", "--listen", seed)
        await asyncio.wait_for(line(router), 30)
        names = [f"r{i:03d}" for i in range(size)]
        workers = [
            await spawn(
                sys.executable,
                __file__,
                "--worker",
                "--names",
                ",".join(names[w :: args.workers]),
                "--size",
                str(size),
                "--cells",
                "on" if cells else "off",
                "--density",
                str(args.density),
                "--range",
                str(args.range),
                "--rate",
                str(args.rate),
            )
            for w in range(min(args.workers, size))
        ]
        await asyncio.wait_for(asyncio.gather(*(line(w) for w in workers)), 900)
        t0 = time.monotonic() + WARM_UP
        t1 = t0 + args.seconds
        for w in workers:
            assert w.stdin is not None
            w.stdin.write(f"run {t0} {t1}\n".encode())
        pids = [p.pid for p in procs]
        await asyncio.sleep(t0 - time.monotonic())
        before = cpu_seconds(pids)
        await asyncio.sleep(t1 - time.monotonic())
        cpu = (cpu_seconds(pids) - before) / (t1 - t0)
        got = sum(json.loads(text)["got"] for text in await asyncio.gather(*map(line, workers)))
    finally:
        for p in procs:
            if p.returncode is None:
                p.kill()
            await p.wait()
    delivered = got / args.seconds / size
    label = "cells" if cells else "flat"
    print(
        f"{size:4d} robots, {label:5}: {cpu:.3f} CPU-s/s, {delivered:.2f} msgs/s a robot",
        flush=True,
    )
    return {"cpu": cpu, "delivered": delivered}


async def main(args: argparse.Namespace) -> dict[str, Any]:
    sizes = [int(s) for s in args.sizes.split(",")]
    out: dict[str, Any] = {
        "radio_setup": f"{args.workers} processes, one node per robot, clients of one router",
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
    p.add_argument("--workers", type=int, default=4, help="processes holding the robots (4)")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--names", help=argparse.SUPPRESS)
    p.add_argument("--size", type=int, help=argparse.SUPPRESS)
    p.add_argument("--cells", help=argparse.SUPPRESS)
    arguments = p.parse_args()
    if arguments.worker:
        asyncio.run(worker(arguments))
    else:
        print(json.dumps(asyncio.run(main(arguments))))
