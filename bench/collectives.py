"""Latency and message counts of distributed_or / distributed_and across robot processes.

    python bench/collectives.py [--sizes 2,5,10,20] [--rounds 40] [--seed 1]

For each team size n (n member processes over zenoh on 127.0.0.1, no world): p50/p99 of
OR latency — from the first member's operation finishing to the last member's continuation —
and AND latency — from the last member finishing to the last continuation — for the
designated-member variant; and messages per step (signed envelopes: requests and replies,
summed over members) for OR, AND all-to-all and AND designated, beside n, n² and the bounds
(OR 2n, AND designated 2(n-1), AND all-to-all 2n(n-1)). In the same run, the raw floor of an
OR step (the winner's one zenoh put to every member and the losers' cancel, no mover) gives
``or_ratio_vs_raw_N = or_p50_ms_N / or_raw_p50_ms_N``. The last line is one JSON object.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mover import Node, NodeConfig, TeamCredentials, launch
from mover._config import free_port

MEMBER = str(Path(__file__).with_name("_member.py"))


def pct(values: list[float], q: int) -> float:
    return statistics.quantiles(values, n=100, method="inclusive")[q - 1]


async def measure(n: int, rounds: int, seed: int) -> dict[str, float]:
    team = TeamCredentials.generate("bench")
    port = free_port()
    env = {**os.environ, **team.env(), **NodeConfig(connect=(f"tcp/127.0.0.1:{port}",)).env()}
    names = [f"m{i:02d}" for i in range(n)]
    procs = []
    async with Node(
        "launcher",
        team,
        kind="tool",
        observer=True,
        config=NodeConfig(listen=(f"tcp/127.0.0.1:{port}",)),
    ) as node:
        try:
            for name in names:
                p = await asyncio.create_subprocess_exec(
                    sys.executable,
                    MEMBER,
                    "--name",
                    name,
                    env=env,
                    stdin=asyncio.subprocess.PIPE,
                    stdout=asyncio.subprocess.PIPE,
                )
                procs.append(p)
            for p in procs:
                assert p.stdout is not None
                await asyncio.wait_for(p.stdout.readline(), 60)
            await node.membership.wait_for(names, timeout=60)
            await asyncio.sleep(1.0)
            or_runs = await launch(node, "bench_or", names, {"rounds": rounds}, run=f"or{n}")
            raw_runs = await launch(node, "bench_raw_or", names, {"rounds": rounds}, run=f"raw{n}")
            and_runs = await launch(
                node,
                "bench_and",
                names,
                {"rounds": rounds, "designated": True, "seed": seed},
                run=f"and{n}",
            )
            all_runs = await launch(
                node,
                "bench_and",
                names,
                {"rounds": max(5, rounds // 4), "designated": False, "seed": seed},
                run=f"all{n}",
            )
        finally:
            for p in procs:
                p.kill()
                await p.wait()
    for runs in (or_runs, raw_runs, and_runs, all_runs):
        failed = {m: o["error"] for m, o in runs.items() if "error" in o}
        if failed:
            raise RuntimeError(f"n={n}: {failed}")

    def or_stats(runs: dict[str, Any]) -> tuple[list[float], list[int]]:
        per_member = [o["result"] for o in runs.values()]
        lat, msgs = [], []
        for k in range(rounds):
            rows = [r[k] for r in per_member]
            if len({r[2] for r in rows}) != 1:
                raise RuntimeError(f"n={n}: members disagreed on a winner")
            first = min(r[0] for r in rows if r[0] > 0)
            lat.append((max(r[1] for r in rows) - first) * 1000)
            msgs.append(sum(r[3] for r in rows))
        return lat, msgs

    or_lat, or_msgs = or_stats(or_runs)
    raw_lat, _ = or_stats(raw_runs)

    def and_stats(runs: dict[str, Any], count: int) -> tuple[list[float], list[int]]:
        members = [o["result"] for o in runs.values()]
        lat, msgs = [], []
        for k in range(count):
            rows = [m[k] for m in members]
            lat.append((max(r[1] for r in rows) - max(r[0] for r in rows)) * 1000)
            msgs.append(sum(r[2] for r in rows))
        return lat, msgs

    and_lat, and_msgs = and_stats(and_runs, rounds)
    _, all_msgs = and_stats(all_runs, max(5, rounds // 4))
    return {
        "or_p50_ms": round(statistics.median(or_lat), 3),
        "or_p99_ms": round(pct(or_lat, 99), 3),
        "or_raw_p50_ms": round(statistics.median(raw_lat), 3),
        "or_ratio_vs_raw": round(statistics.median(or_lat) / statistics.median(raw_lat), 3),
        "and_p50_ms": round(statistics.median(and_lat), 3),
        "and_p99_ms": round(pct(and_lat, 99), 3),
        "or_msgs": round(statistics.mean(or_msgs), 2),
        "and_all_msgs": round(statistics.mean(all_msgs), 2),
        "and_designated_msgs": round(statistics.mean(and_msgs), 2),
    }


async def main(args: argparse.Namespace) -> None:
    figures: dict[str, float] = {}
    print(f"seed {args.seed}, {args.rounds} rounds per collective")
    print(
        f"{'n':>3} {'OR p50':>8} {'OR p99':>8} {'raw OR':>8} {'ratio':>6} "
        f"{'AND p50':>8} {'AND p99':>8} "
        f"{'OR msgs':>8} {'<=2n':>5} {'AND-d':>6} {'<=2(n-1)':>8} {'AND-all':>8} "
        f"{'2n(n-1)':>8} {'n^2':>5}"
    )
    for n in args.sizes:
        r = await measure(n, args.rounds, args.seed)
        print(
            f"{n:>3} {r['or_p50_ms']:>8.2f} {r['or_p99_ms']:>8.2f} {r['or_raw_p50_ms']:>8.2f} "
            f"{r['or_ratio_vs_raw']:>6.2f} {r['and_p50_ms']:>8.2f} "
            f"{r['and_p99_ms']:>8.2f} {r['or_msgs']:>8.1f} {2 * n:>5} "
            f"{r['and_designated_msgs']:>6.1f} {2 * (n - 1):>8} {r['and_all_msgs']:>8.1f} "
            f"{2 * n * (n - 1):>8} {n * n:>5}",
            flush=True,
        )
        for key, value in r.items():
            figures[f"{key}_{n}"] = value
    print(json.dumps(figures))


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], default=[2, 5, 10, 20])
    p.add_argument("--rounds", type=int, default=40)
    p.add_argument("--seed", type=int, default=1)
    asyncio.run(main(p.parse_args()))
