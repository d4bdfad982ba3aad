"""Seeing into a team from a terminal: ``mover call ROBOT --list`` (the exported procedures,
their signatures and docstrings) and ``mover echo TOPIC`` (decoded broadcasts with sender,
distance and bearing), as real processes over zenoh."""

from __future__ import annotations

import asyncio
import json
import os
import sys
from pathlib import Path

import pytest

from mover import Node
from mover.testing import Cluster, cluster

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]


def _env(c: Cluster) -> dict[str, str]:
    return {**os.environ, **c.env, **c.team.env(), **c.peer.env()}


async def _mover(c: Cluster, *args: str, bound: float = 30.0) -> tuple[int, str, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *args, env=_env(c), cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    try:
        out, err = await asyncio.wait_for(proc.communicate(), bound)
    finally:
        if proc.returncode is None:  # a failed or cancelled test leaves no process behind
            proc.kill()
            await proc.wait()
    assert proc.returncode is not None
    return proc.returncode, out.decode(), err.decode()


class _At:
    def __init__(self, pose: tuple[float, float, float]) -> None:
        self.pose = pose

    def position(self) -> tuple[float, float, float]:
        return self.pose


def add(a: int, b: int = 2) -> int:
    """Add two numbers.

    More that the listing leaves out."""
    return a + b


async def test_call_list_shows_procedures_signatures_and_docstrings() -> None:
    async with cluster() as c, c.launcher() as node:
        node.export(add)
        code, out, err = await _mover(c, "call", "launcher", "--list", "--wait", "10")
        assert code == 0, err
        lines = out.splitlines()
        assert "add(a: int, b: int = 2) -> int  Add two numbers." in lines
        assert not any(line.startswith("mover.") for line in lines)  # the protocol's: --all
        assert "of mover's own procedures (mover.*) not shown: --all" in out
        assert not any("More that" in line for line in lines)
        code, out, err = await _mover(c, "call", "launcher", "--list", "--all", "--wait", "10")
        assert code == 0, err
        assert "mover.procedures() -> dict[str, dict[str, str]]  What this node exports" in out
        code, _, err = await _mover(c, "call", "launcher", "add", "--all")
        assert code == 2 and "--all goes with --list" in err
        code, _, err = await _mover(c, "call", "launcher", "add", "--list")
        assert code == 2 and "--list takes no procedure" in err and "Traceback" not in err
        code, _, err = await _mover(c, "call", "launcher")
        assert code == 2 and "name a procedure" in err


async def test_echo_prints_decoded_messages_with_distance_from_its_place() -> None:
    async with cluster() as c, c.launcher() as node:
        async with Node("ernst", c.team, config=c.peer, locator=_At((0.0, 0.0, 0.0))) as ernst:
            await node.membership.wait_for(["ernst"], timeout=10)
            echo = asyncio.ensure_future(
                _mover(c, "echo", "hello", "--at", "1,0,3.14159", "--count", "2", "--json")
            )
            await asyncio.sleep(3.0)  # the echo's node joins and hears ernst's hello
            await ernst.broadcast("hello", {"n": 1}, reliable=True)  # team-wide
            await ernst.broadcast("hello", {"n": 2}, range=0.5, reliable=True)  # out of reach
            await ernst.broadcast("hello", {"n": 3}, range=3.0, reliable=True)
            code, out, err = await asyncio.wait_for(echo, 30)
        assert code == 0, err
        got = [json.loads(line) for line in out.splitlines()]
        assert [m["data"]["n"] for m in got] == [1, 3]
        assert all(m["sender"] == "ernst" for m in got)
        assert abs(got[1]["distance"] - 1.0) < 1e-6
        assert abs(got[1]["bearing"]) < 1e-3  # ahead: the echo faces ernst (heading π)
        code, _, err = await _mover(c, "echo", "mover/*")
        assert code == 2 and "not a topic" in err
        code, _, err = await _mover(c, "echo", "hello", "--at", "1,nan")
        assert code == 2 and "--at" in err


async def test_echo_says_what_it_waits_for_when_nothing_comes() -> None:
    async with cluster() as c, c.launcher():
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "mover", "echo", "quiet/topic", env=_env(c), cwd=ROOT,
            stdout=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.PIPE,
        )  # fmt: skip
        said: list[str] = []
        try:
            async with asyncio.timeout(20):
                while not any("nothing on" in line for line in said):
                    said.append((await proc.stderr.readline()).decode())  # type: ignore[union-attr]
        finally:
            proc.kill()
            await proc.wait()
    told = "".join(said)
    assert "nothing on 'quiet/topic' for 5 s; still listening" in told
    assert "--at a place within their range" in told
