"""A process that takes a name a live member holds refuses to start, naming the holder (real
processes over zenoh on 127.0.0.1); the holder is unaffected. The same for worlds."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

import pytest

from mover.testing import cluster

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]
WORLD = str(ROOT / "worlds" / "search_and_rescue.toml")


async def _second(env: dict[str, str], *args: str) -> tuple[int, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, *args, env=env, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    out, err = await asyncio.wait_for(proc.communicate(), 30)
    assert proc.returncode is not None
    return proc.returncode, (out + err).decode()


async def test_a_duplicate_robot_or_world_name_is_refused() -> None:
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        first = await c.start("robots", "--name", "r1", "--hardware", "none")
        await c.start("mover._cli", "world", WORLD, "--name", "w1", ready=None)
        await node.membership.wait_for({"r1", "w1"}, timeout=20)
        env = {**os.environ, **c.env, **c.team.env(), **c.peer.env()}
        code, text = await _second(env, "-m", "robots", "--name", "r1", "--hardware", "none")
        assert code == 2 and "Traceback" not in text
        lines = [line for line in text.splitlines() if "taken" in line]
        assert len(lines) == 1 and f"pid {first.pid}" in lines[0], text
        code, text = await _second(env, "-m", "mover._cli", "world", WORLD, "--name", "w1")
        assert code == 2 and "Traceback" not in text and "the name 'w1' is taken" in text, text
        # the holders are unaffected
        assert "r1" in node.membership and "w1" in node.membership
        info = node.membership.info("r1")
        assert info is not None and info.pid == first.pid
