"""Does a seeded lock-step run repeat however its processes are scheduled?

    python bench/repeats.py [--runs 8] [--seed 7] [--hogs 2] [--stalls] [--control-delay K]
                            [--out DIR]

Runs ``mover demo --seed SEED`` (search and rescue on real processes) ``--runs`` times beside
``--hogs`` busy-loop processes, on a world with ``--control-delay K`` (default 0), with
``--stalls`` its processes SIGSTOPped for moments of up to 0.3 s (``mover.testing.stutter``,
seeded by the run's number), and counts the distinct recordings (``world.jsonl``, byte for
byte) and the distinct reports (the demo's report without its wall-clock figures). One run in
each is the baseline: the same command on the same machine. Where recordings part, the first
tick whose commands differ is printed.

Each run prints one line; the last line is one JSON object: ``runs``, ``seed``, ``hogs``,
``stalls``, ``control_delay``, ``recordings`` and ``reports`` (distinct counts: 1 and 1 when
runs repeat), ``failed`` (runs that did not end with status 0), ``wall_s`` (median seconds a
run).
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from experiments.demo_runs import first_difference, report, run_demo  # noqa: E402
from mover.testing import cpu_hogs  # noqa: E402


async def main(args: argparse.Namespace) -> dict[str, object]:
    base = Path(args.out or tempfile.mkdtemp(prefix="repeats-"))
    recordings: dict[str, Path] = {}
    reports: set[str] = set()
    failed, walls = 0, []
    with cpu_hogs(args.hogs):
        for i in range(args.runs):
            out = base / f"run{i}"
            t0 = time.perf_counter()
            stall = i if args.stalls else None
            code, text = await run_demo(
                out,
                *("--seed", str(args.seed), "--control-delay", str(args.control_delay)),
                stall_seed=stall,
            )
            wall = time.perf_counter() - t0
            walls.append(wall)
            if code != 0:
                failed += 1
                print(f"run {i}: status {code}; output in {out}")
                continue
            recording = out / "world.jsonl"
            digest = hashlib.sha256(recording.read_bytes()).hexdigest()[:16]
            said = ""
            if recordings and digest not in recordings:
                first = first_difference(next(iter(recordings.values())), recording)
                said = "; " + first.replace("\n", "; ")
            recordings.setdefault(digest, recording)
            reports.add("\n".join(report(text)))
            print(f"run {i}: recording {digest}, {wall:.1f} s{said}")
    return {
        "runs": args.runs,
        "seed": args.seed,
        "hogs": args.hogs,
        "stalls": args.stalls,
        "control_delay": args.control_delay,
        "recordings": len(recordings),
        "reports": len(reports),
        "failed": failed,
        "wall_s": round(statistics.median(walls), 1),
    }


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=8, help="demo runs (default 8)")
    parser.add_argument("--seed", type=int, default=7, help="the demo's seed (default 7)")
    parser.add_argument("--hogs", type=int, default=2, help="busy loops beside (default 2)")
    parser.add_argument("--stalls", action="store_true", help="SIGSTOP its processes briefly")
    parser.add_argument("--control-delay", type=int, default=0, help="ticks (default 0)")
    parser.add_argument("--out", help="folder for the runs' output (default: a new temporary)")
    parsed = parser.parse_args()
    if not 1 <= parsed.runs <= 100 or not 0 <= parsed.hogs <= 16:
        parser.error("--runs must be 1..100 and --hogs 0..16")
    if not 0 <= parsed.control_delay <= 100:
        parser.error("--control-delay must be 0..100")
    print(json.dumps(asyncio.run(main(parsed))))
