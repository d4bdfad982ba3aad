"""`mover demo` end to end: a world process, robot processes, a program, a report and a PNG."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

from tests.helpers.procs import ROOT


async def run_demo(tmp_path: Path, *args: str) -> tuple[int, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "mover._cli",
        "demo",
        "--out",
        str(tmp_path),
        *args,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.STDOUT,
    )
    out, _ = await asyncio.wait_for(proc.communicate(), 120)
    return proc.returncode or 0, out.decode()


async def test_hello_team_demo_runs_on_processes(tmp_path: Path) -> None:
    code, out = await run_demo(tmp_path, "--program", "hello_team")
    assert code == 0, out
    assert "ernst: heard who=[moseley]" in out
    assert "step 1 (and): 2 messages for 2 members (bound 2)" in out
    assert (tmp_path / "trajectories.png").stat().st_size > 1000
