"""A loaded machine, for tests of reproducibility: CPU hogs beside a run, and short SIGSTOPs of
its processes (a seeded lock-step run must give the same recording however its processes are
scheduled). Every process started or stopped here is resumed and ended, also on failure.
Linux only (it reads /proc)."""

from __future__ import annotations

import asyncio
import contextlib
import os
import random
import signal
import subprocess
import sys
from collections.abc import AsyncIterator, Iterator
from pathlib import Path


@contextlib.contextmanager
def cpu_hogs(n: int) -> Iterator[list[subprocess.Popen[bytes]]]:
    """``n`` processes that spin for the duration of the block."""
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    try:
        yield hogs
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()


def descendants(pid: int) -> list[int]:
    """The processes below ``pid`` (children, their children, ...), read from /proc."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, ValueError, IndexError):
            fields = stat.read_text().rsplit(")", 1)[1].split()
            parents.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out


@contextlib.asynccontextmanager
async def stutter(
    pid: int, seed: int, *, every: float = 0.7, longest: float = 0.3
) -> AsyncIterator[list[tuple[int, float]]]:
    """While the block runs, every ``every`` s SIGSTOP one process below ``pid`` (chosen by
    ``seed``) for up to ``longest`` s, then SIGCONT it: short stalls, below a member's lease.
    Yields the list of (pid, seconds) stops made."""
    rng = random.Random(seed)
    stops: list[tuple[int, float]] = []

    async def run() -> None:
        while True:
            await asyncio.sleep(every)
            procs = descendants(pid)
            if not procs:
                continue
            victim, pause = rng.choice(sorted(procs)), rng.uniform(0.05, longest)
            try:
                os.kill(victim, signal.SIGSTOP)
            except ProcessLookupError:  # it ended meanwhile
                continue
            try:
                await asyncio.sleep(pause)
            finally:
                # a victim that ended while stopped (its run killed it) is not resumed; and a
                # cancellation here goes on (a suppressed error around the finally swallowed
                # it, and the block's end waited for this loop forever)
                with contextlib.suppress(ProcessLookupError):
                    os.kill(victim, signal.SIGCONT)
            stops.append((victim, pause))

    task = asyncio.ensure_future(run())
    try:
        yield stops
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
