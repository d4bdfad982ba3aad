"""Large payloads do not fault in fresh pages, whatever the process freed before
(mover/_allocator.py).

With glibc's moving thresholds, once a process has freed one mapped 1 MiB block, every later pair
of 1 MiB blocks freed at the heap's top trims the heap, and the next pair faults its two
megabytes in again (~480 minor page faults; a 1 MiB call holds such a pair, docs/transport.md).
A node holds the thresholds fixed. Page faults are counted, which the machine's load does not
change.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.helpers.procs import ROOT

pytestmark = pytest.mark.processes

PAIRS = """
import asyncio, resource
from mover import Node, NodeConfig, TeamCredentials
from mover._allocator import hold_thresholds
from mover._config import free_port


async def main():
    config = NodeConfig(listen=(f"tcp/127.0.0.1:{free_port()}",))
    async with Node("lone", TeamCredentials.generate("solo"), config=config):
        block = b"\\1" * (1 << 20)  # a mapped block, freed: glibc would move its thresholds
        del block
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        for _ in range(20):
            a = b"\\1" * (1 << 20)
            b = b"\\2" * (1 << 20)
            del b, a
        faults = (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 20
        print(hold_thresholds(), faults)

asyncio.run(main())
"""


def _run(code: str, **env: str) -> list[str]:
    return _process(code, **env).stdout.split()


def _process(code: str, **env: str) -> subprocess.CompletedProcess[str]:
    clean = {k: v for k, v in os.environ.items() if not k.startswith(("MALLOC_", "MOVER_ALLOC"))}
    return subprocess.run(
        [sys.executable, "-c", code], env={**clean, **env}, cwd=ROOT,
        capture_output=True, text=True, check=True, timeout=60,
    )  # fmt: skip


def test_the_thresholds_are_held_unless_the_user_chose() -> None:
    code = "from mover._allocator import hold_thresholds as h; print(h(), h())"
    assert _run(code) == ["True", "True"]
    assert _run(code, MOVER_ALLOCATOR="default") == ["False", "False"]
    assert _run(code, MALLOC_TRIM_THRESHOLD_="1048576") == ["False", "False"]
    out = _process(code, MOVER_ALLOCATOR="defualt")
    assert out.stdout.split() == ["True", "True"]  # a typo is said, once, and held
    assert out.stderr.count("MOVER_ALLOCATOR='defualt' is not 'default' or 'held'") == 1
    assert "Traceback" not in out.stderr


def test_large_blocks_after_a_freed_mapped_one_fault_in_no_fresh_pages() -> None:
    held, faults = _run(PAIRS)
    assert held == "True"
    assert float(faults) < 64, f"{faults} minor page faults a pair of 1 MiB blocks"
