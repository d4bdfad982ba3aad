"""Search and rescue across three hosts (router and world; robots behind a proxy; the
workstation's ``mover run``), every process a client of the router over mutual TLS: it
completes on a clean network, and its recording is the one machine's, byte for byte."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

import pytest

from mover._netteam import last_tick, losses
from mover._up import load_team
from mover.testing import Netlab, TeamAcrossHosts
from tests.helpers.procs import ROOT
from tests.netlab import LAB

pytestmark = LAB

SEED = 1


async def one_machine(out: Path) -> None:
    """``mover demo`` with the same seed: the same team file's run on one machine."""
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover._cli", "demo", "--seed", str(SEED), "--out", str(out),
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT,
    )  # fmt: skip
    said, _ = await asyncio.wait_for(proc.communicate(), 120)
    assert proc.returncode == 0, said.decode()


@pytest.mark.timeout(300)
async def test_search_and_rescue_across_hosts_repeats_the_one_machine_run(tmp_path: Path) -> None:
    plan = load_team(ROOT / "teams" / "search_and_rescue.toml")
    async with (
        Netlab(("a", "b", "c")) as lab,
        TeamAcrossHosts(lab, plan, out=tmp_path / "hosts", seed=SEED) as team,
    ):
        result = await team.run_program(timeout=120)
        assert team.proxy is not None and team.proxy.stats.connections == 3  # b's robots
        lost = losses(result, team)  # before the stop, whose leaving the world logs
    print(result.text)
    assert result.code == 0
    assert result.text.count(": done") == 3
    assert lost == {}
    assert team.tracebacks() == {}
    assert result.run_s is not None
    sim = last_tick(team.recording)
    assert sim is not None and sim > 100
    print(f"across hosts: {sim:.1f} simulated s in {result.run_s:.1f} s")
    assert lab.leftovers() == []

    await one_machine(tmp_path / "one")
    assert (tmp_path / "one" / "world.jsonl").read_bytes() == team.recording.read_bytes()
