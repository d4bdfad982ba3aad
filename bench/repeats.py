"""Does a seeded lock-step run repeat however its processes are scheduled?

    python bench/repeats.py [--runs 8] [--seed 7] [--hogs 2] [--stalls] [--out DIR]

Runs ``mover demo --seed SEED`` (search and rescue on real processes) ``--runs`` times beside
``--hogs`` busy-loop processes, with ``--stalls`` its processes SIGSTOPped for moments of up to
0.3 s (``mover.testing.stutter``, seeded by the run's number), and counts the distinct
recordings (``world.jsonl``, byte for byte) and the distinct reports (the demo's report without
its wall-clock figures). One run in each is the baseline: the same command on the same machine.
Where recordings part, the first tick whose commands differ is printed.

Each run prints one line; the last line is one JSON object: ``runs``, ``seed``, ``hogs``,
``stalls``, ``recordings`` and ``reports`` (distinct counts: 1 and 1 when runs repeat),
``failed`` (runs that did not end with status 0), ``wall_s`` (median seconds a run).
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import os
import re
import statistics
import sys
import tempfile
import time
from contextlib import AsyncExitStack
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mover.testing import cpu_hogs, stutter  # noqa: E402
from sim_hw.continuous import read_recording  # noqa: E402


def report(out: str) -> str:
    """The demo's report without its wall-clock figures."""
    text = out.split("== report ==", 1)[-1]
    kept = [
        re.sub(r"wall +\d+\.\d+ +", "", line)
        for line in text.splitlines()
        if not line.startswith(("wall time", "trajectories:"))
    ]
    return "\n".join(kept)


def first_difference(a: Path, b: Path) -> str:
    """The first tick whose commands differ between two recordings."""
    one, two = ({t["tick"]: t for t in read_recording(p)[1]} for p in (a, b))
    for tick in sorted(set(one) & set(two)):
        if one[tick]["commands"] != two[tick]["commands"]:
            return f"commands first differ at tick {tick}"
    return "commands agree on every tick both have"


async def run_once(out: Path, seed: int, stall: int | None) -> tuple[int, str, float]:
    """One ``mover demo``; its status, output and wall seconds."""
    t0 = time.perf_counter()
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "mover",
        "demo",
        "--seed",
        str(seed),
        "--out",
        str(out),
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.STDOUT,
    )
    async with AsyncExitStack() as stack:
        if stall is not None:
            await stack.enter_async_context(stutter(proc.pid, stall))
        text, _ = await asyncio.wait_for(proc.communicate(), 300)
    return proc.returncode or 0, text.decode(), time.perf_counter() - t0


async def main(args: argparse.Namespace) -> dict[str, object]:
    base = Path(args.out or tempfile.mkdtemp(prefix="repeats-"))
    recordings: dict[str, Path] = {}
    reports: set[str] = set()
    failed, walls = 0, []
    with cpu_hogs(args.hogs):
        for i in range(args.runs):
            out = base / f"run{i}"
            code, text, wall = await run_once(out, args.seed, i if args.stalls else None)
            walls.append(wall)
            if code != 0:
                failed += 1
                print(f"run {i}: status {code}; output in {out}")
                continue
            recording = out / "world.jsonl"
            digest = hashlib.sha256(recording.read_bytes()).hexdigest()[:16]
            said = ""
            if recordings and digest not in recordings:
                said = "; " + first_difference(next(iter(recordings.values())), recording)
            recordings.setdefault(digest, recording)
            reports.add(report(text))
            print(f"run {i}: recording {digest}, {wall:.1f} s{said}")
    return {
        "runs": args.runs,
        "seed": args.seed,
        "hogs": args.hogs,
        "stalls": args.stalls,
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
    parser.add_argument("--out", help="folder for the runs' output (default: a new temporary)")
    parsed = parser.parse_args()
    if not 1 <= parsed.runs <= 100 or not 0 <= parsed.hogs <= 16:
        parser.error("--runs must be 1..100 and --hogs 0..16")
    print(json.dumps(asyncio.run(main(parsed))))
