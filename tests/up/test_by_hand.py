"""A team started by hand, one process at a time, on loopback: each says what is missing.

The world's READY line names the exact endpoint (the port zenoh chose for ``:0``) and the
variables robots need; a robot started without them says every few seconds which world it
waits for, where it looks and what to set; started as the READY line says, it joins.
"""

from __future__ import annotations

import asyncio
import os
import re
import sys
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from mover import Node, NodeConfig, TeamCredentials
from mover._endpoints import bound, join_hint
from tests.helpers.procs import ROOT, terminate

pytestmark = pytest.mark.processes

WORLD = ROOT / "worlds" / "search_and_rescue.toml"


def test_a_free_port_is_named_as_this_process_listens_on_it() -> None:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        assert bound(["tcp/127.0.0.1:0", "tcp/127.0.0.1:7447"]) == [
            f"tcp/127.0.0.1:{port}",
            "tcp/127.0.0.1:7447",
        ]
    assert bound(["tcp/127.0.0.1:0"]) == []  # closed: nothing to name


def test_the_hint_says_where_the_process_looks_and_what_to_set() -> None:
    nothing = join_hint(team="t", connect=(), linked=False, awaited="the world")
    assert "MOVER_CONNECT is not set" in nothing and "READY line of the world" in nothing
    silent = join_hint(team="t", connect=("tcp/10.0.0.5:7447",), linked=False, awaited="the world")
    assert "nothing answers at tcp/10.0.0.5:7447" in silent
    elsewhere = join_hint(team="t", connect=("tcp/h:1",), linked=True, awaited="the world")
    assert "not in team 't'" in elsewhere and "team key" in elsewhere


@asynccontextmanager
async def started(*args: str, env: dict[str, str]) -> AsyncIterator[asyncio.subprocess.Process]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover._cli", *args, cwd=ROOT,
        env={**env, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"},
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT,
    )  # fmt: skip
    try:
        yield proc
    finally:
        await terminate(proc, 15)


async def lines_until(proc: asyncio.subprocess.Process, pattern: str, timeout: float) -> list[str]:
    """Its lines up to one that matches ``pattern`` (TimeoutError after ``timeout`` s)."""
    assert proc.stdout is not None
    seen: list[str] = []
    async with asyncio.timeout(timeout):
        while not seen or not re.search(pattern, seen[-1]):
            raw = await proc.stdout.readline()
            assert raw, f"ended: {seen[-5:]}"
            seen.append(raw.decode(errors="replace").rstrip())
    return seen


@pytest.mark.timeout(120)
async def test_started_by_hand_each_process_says_what_is_missing(tmp_path: Path) -> None:
    team = TeamCredentials.generate("byhand")
    key = tmp_path / "team.key"
    key.write_text(team.key.hex() + "\n")
    base = {k: v for k, v in os.environ.items() if not k.startswith("MOVER_")}
    base |= {"MOVER_TEAM": team.name, "MOVER_TEAM_KEY_FILE": str(key)}
    async with started("world", str(WORLD), env=base) as world:
        said = await lines_until(world, r"^READY ", 60)
        ready = said[-1]
        print(ready)
        endpoint = re.search(r"MOVER_CONNECT=(tcp/127\.0\.0\.1:(\d+))", ready)
        assert endpoint is not None and endpoint.group(2) != "0", ready
        assert f"MOVER_TEAM=byhand MOVER_CONNECT={endpoint.group(1)} " in ready
        assert f"MOVER_TEAM_KEY_FILE={key}" in ready

        # a robot without MOVER_CONNECT: it says so, again and again
        async with started("robot", "--name", "elvis", env=base) as lost:
            t0 = time.monotonic()
            waits: list[tuple[float, str]] = []
            while len(waits) < 2:
                line = (await lines_until(lost, r"waiting for the hardware", 30))[-1]
                waits.append((time.monotonic() - t0, line))
        print("\n".join(f"{t:5.1f} s {line}" for t, line in waits))
        assert "world 'world'" in waits[0][1]
        assert "MOVER_CONNECT is not set" in waits[0][1]
        assert "READY line of the world" in waits[0][1]
        assert 4.0 < waits[1][0] - waits[0][0] < 9.0  # every few seconds, not once

        # as the READY line says: it joins
        env = base | {"MOVER_CONNECT": endpoint.group(1)}
        async with (
            started("robot", "--name", "elvis", env=env),
            Node("test", team, kind="tool", config=NodeConfig(connect=(endpoint.group(1),))) as me,
        ):
            await me.membership.wait_for({"world", "elvis"}, timeout=30)
