"""The `mover` command against real robot processes."""

from __future__ import annotations

import asyncio
import json
import os
import sys

from mover import Node
from tests.helpers.procs import ROOT, cluster


async def mover(*args: str, env: dict[str, str]) -> tuple[int, str, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "mover._cli",
        *args,
        env={**os.environ, **env},
        cwd=ROOT,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    out, err = await asyncio.wait_for(proc.communicate(), 60)
    return proc.returncode or 0, out.decode(), err.decode()


async def test_ps_and_call() -> None:
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        await c.robot("r1", "--kind", "foot-bot")
        await node.team.wait_for({"r1"}, timeout=10)
        env = {**c.team.env(), **c.peer.env()}
        code, out, err = await mover("ps", "--wait", "1.5", "--json", env=env)
        assert code == 0, err
        rows = {r["name"]: r for r in map(json.loads, out.splitlines())}
        assert rows["r1"]["kind"] == "foot-bot" and rows["tester"]["kind"] == "test"
        assert not any(n.startswith("ps-") for n in rows)  # the tool is not a member

        code, out, err = await mover("call", "r1", "add", "2", "40", env=env)
        assert (code, out) == (0, "42\n"), err
        code, _, err = await mover("call", "r1", "boom", '"no"', env=env)
        assert code == 1 and "RemoteError" in err and "ValueError: no" in err
        code, _, err = await mover("call", "r1", "add", "1", env=env)
        assert code == 1 and "BadArguments" in err
        code, _, err = await mover("call", "r9", "add", "1", "--wait", "0.5", env=env)
        assert code == 1 and "no member 'r9'" in err
        code, _, err = await mover("call", "r1", "add", "two", env=env)
        assert code == 2 and "argument 1 is not JSON" in err
        wrong = {**env, "MOVER_TEAM_KEY": "00" * 32}
        code, _, err = await mover("call", "r1", "add", "1", "2", env=wrong)
        assert code == 1 and "no member 'r1'" in err  # an outsider cannot even see members
