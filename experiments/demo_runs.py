"""``mover demo`` as a process, and two of its runs compared: what the demo's tests and
``bench/repeats.py`` share.

:func:`run_demo` runs it (optionally with its processes SIGSTOPped for moments, as on a loaded
machine); :func:`report` is its report without the wall-clock figures (what must repeat);
:func:`first_difference` says where two recordings of one world part.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import signal
import sys
from pathlib import Path

from mover.testing import descendants, stutter
from sim_hw.continuous import read_recording

ROOT = Path(__file__).resolve().parents[1]


async def run_demo(
    out: Path, *args: str, stall_seed: int | None = None, timeout: float = 180.0
) -> tuple[int, str]:
    """``mover demo --out OUT ARGS`` from the repository; its exit status and output. With
    ``stall_seed``, its processes are SIGSTOPped for short moments as it runs
    (:func:`mover.testing.stutter`, seeded)."""
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "mover",
        "demo",
        "--out",
        str(out),
        *args,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.STDOUT,
    )
    if stall_seed is None:
        text = await _bounded(proc, timeout)
    else:
        async with stutter(proc.pid, stall_seed) as stops:
            text = await _bounded(proc, timeout)
        print(f"{len(stops)} stops of the demo's processes, {sum(s for _, s in stops):.1f} s")
    return proc.returncode or 0, text.decode()


async def _bounded(proc: asyncio.subprocess.Process, timeout: float) -> bytes:
    """The demo's output once it ends; past ``timeout`` s its processes are killed (the demo
    last) and what it printed is returned with a last line saying so: a demo that hangs fails
    its caller with its own output, not at the test's time limit without it."""
    task = asyncio.ensure_future(proc.communicate())
    done, _ = await asyncio.wait({task}, timeout=timeout)
    if done:
        return task.result()[0]
    for pid in [*descendants(proc.pid), proc.pid]:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    text, _ = await asyncio.wait_for(task, 30)
    return text + f"\nrun_demo: no end after {timeout:.0f} s: its processes killed\n".encode()


def report(out: str) -> list[str]:
    """The demo's report without its wall-clock figures: outcomes, simulated phase times,
    messages per step, how far each box moved."""
    lines = out.split("== report ==", 1)[-1].splitlines()
    kept = []
    for line in lines:
        if line.startswith("wall time") or line.startswith("trajectories:"):
            continue
        kept.append(re.sub(r"wall +\d+\.\d+ +", "", line))  # a phase: its simulated time only
    return kept


def first_difference(a: Path, b: Path) -> str:
    """Where two recordings of one world part: the first tick whose commands differ, and
    the first whose poses do (a diagnosis for a run that did not repeat)."""
    ticks = [{t["tick"]: t for t in read_recording(p)[1]} for p in (a, b)]
    said = []
    for key in ("commands", "robots"):
        for tick in sorted(set(ticks[0]) & set(ticks[1])):
            one, two = ticks[0][tick][key], ticks[1][tick][key]
            if one != two:
                robots = sorted(r for r in {*one, *two} if one.get(r) != two.get(r))
                said.append(
                    f"{key} first differ at tick {tick}: "
                    + "; ".join(f"{r}: {one.get(r)} against {two.get(r)}" for r in robots)
                )
                break
    ends = [max(t) if t else None for t in ticks]
    return "\n".join(said or [f"the recordings agree up to their ends (ticks {ends})"])
