"""Robot processes and a workstation member, started with `python -m robots`, run a program."""

from __future__ import annotations

import asyncio
import os
import sys

import pytest

from mover import launch
from tests.helpers.procs import ROOT, cluster

pytestmark = pytest.mark.processes


async def test_robot_and_workstation_run_a_program_together() -> None:
    # This is how a user tests a program: mover.testing starts real processes.
    async with cluster() as c, c.launcher() as node:
        await c.world(str(ROOT / "worlds" / "search_and_rescue.toml"), expect=2)
        await c.robots("ernst", "moseley")
        await c.start("robots", "--name", "desk", "--hardware", "none", "--kind", "workstation")
        await node.membership.wait_for(["world", "ernst", "moseley", "desk"], timeout=30)
        assert node.membership.info("desk").kind == "workstation"  # type: ignore[union-attr]
        pose = await node.call("ernst", "robot.pose", timeout=10)
        assert pose[:2] == pytest.approx([0.8, 3.0], abs=0.05)
        outcomes = await launch(node, "hello_team", ["desk", "ernst", "moseley"], {}, run="hi")
        sizes = {m: o["result"]["team_size"] for m, o in outcomes.items()}
        assert sizes == {"desk": 3, "ernst": 3, "moseley": 3}
        assert outcomes["ernst"]["result"]["me"]["nearest"] == "moseley"
        bad = await launch(node, "hello_team", ["ernst", "moseley"], {"listen": -1}, run="bad")
        assert {m: o.get("error") for m, o in bad.items()} == dict.fromkeys(
            ["ernst", "moseley"], "ValueError: listen is -1.0 s; from 0 to 60.0 s"
        )


async def robot_process(*args: str) -> tuple[int, str]:
    """``python -m robots ARGS`` that is expected to stop at once; (exit code, stderr)."""
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "robots",
        *args,
        env={**os.environ, "MOVER_TEAM": "alpha", "MOVER_TEAM_KEY": "ab" * 32},
        cwd=ROOT,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    _, err = await asyncio.wait_for(proc.communicate(), 30)
    return proc.returncode or 0, err.decode()


async def test_unknown_hardware_backend_is_a_clear_error() -> None:
    code, err = await robot_process("--name", "x", "--hardware", "warp")
    assert code == 2
    assert "no hardware backend 'warp'" in err


async def test_an_unknown_backend_option_is_a_one_line_usage_error() -> None:
    code, err = await robot_process("--name", "x", "--hardware", "grid", "--option", "wrld=3")
    assert code == 2
    assert err.splitlines() == [
        "robots: hardware backend 'grid' takes no option 'wrld' "
        "(its options: call_timeout, idle_period, world)"
    ]
    code, err = await robot_process("--name", "x", "--hardware", "none", "--world", "w")
    assert code == 2 and err.startswith("robots: hardware 'none' takes no options")
    code, err = await robot_process("--name", "x", "--option", "timeout", "--log-level", "error")
    assert (code, err) == (2, "robots: --option 'timeout': expected KEY=VALUE\n")
