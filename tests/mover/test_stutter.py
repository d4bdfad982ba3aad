"""``mover.testing.stutter`` ends with its block, also when a process it stopped died stopped."""

from __future__ import annotations

import asyncio
import os
import signal
import sys

import pytest

from mover.testing import descendants, stutter

pytestmark = pytest.mark.processes

PARENT = "import subprocess, time; subprocess.Popen(['sleep', '60']).wait(); time.sleep(60)"
"""A process whose child, once dead, it reaps at once (as a run's processes are reaped)."""


async def test_the_block_ends_when_its_stopped_victim_was_killed() -> None:
    parent = await asyncio.create_subprocess_exec(sys.executable, "-c", PARENT)
    try:
        async with asyncio.timeout(10):
            while not descendants(parent.pid):  # its child is up
                await asyncio.sleep(0.01)
        [child] = descendants(parent.pid)
        async with asyncio.timeout(10):  # a block that never ends fails here, not at the limit
            async with stutter(parent.pid, 1, every=0.01, longest=30.0):
                while "T" not in _state(child):  # the child is stopped (for up to 30 s)
                    await asyncio.sleep(0.01)
                os.kill(child, signal.SIGKILL)  # it dies stopped, and is reaped: it is gone
                while child in descendants(parent.pid):
                    await asyncio.sleep(0.01)
    finally:
        for pid in descendants(parent.pid):  # (a child left by a failure: not for 60 s)
            os.kill(pid, signal.SIGKILL)
        parent.kill()
        await parent.wait()


def _state(pid: int) -> str:
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[0]
