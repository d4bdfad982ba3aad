"""A team across hosts through the faults of a real network (issue 23): a run stalls and resumes,
it is never lost, and a member known dead is still reported at once.

Search and rescue (``teams/search_and_rescue.toml``, the team's patience at its default, 10 s,
the world's control delay 2 ticks as for teams across hosts) across three hosts, every process
a client of one router over mutual TLS (router and world on a, the robots on b behind an
impairment proxy, ``mover run`` on c): through a 5 s partition of b, a 5 s router stall and 10 %
loss at 50 ± 20 ms each way it completes, with the recording of a clean run, no member lost and
no traceback; ``mover run`` says that it waits. Under 2 % loss at 50 ± 20 ms each way
``hello_team`` runs to its end too;
processes started while the router is down say so, wait, and come up with it; a tool gives up
after its patience in one line; a SIGKILLed robot ends the run at once, not after the patience.
"""

from __future__ import annotations

import asyncio
import re
import signal
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest

from mover._impair import Impairment
from mover._netteam import WORKSTATION, RunResult, last_tick, losses
from mover._up import load_team
from mover._up._teamfile import ProgramPlan, TeamPlan
from mover.testing import Netlab, TeamAcrossHosts
from tests.helpers.procs import ROOT
from tests.netlab import LAB

pytestmark = LAB

SEED = 1
HOSTS = ("a", "b", "c")
CONTROL_DELAY = 2  # bench/network.py's: a 100 ms round trip in real time
LOSSY = Impairment(0.05, 0.02, loss=0.1)  # 10 % loss at 50 ± 20 ms each way


def rescue() -> TeamPlan:
    return load_team(ROOT / "teams" / "search_and_rescue.toml")


def completed(
    result: RunResult, team: TeamAcrossHosts, lost: dict[str, int], end: str = ": done"
) -> None:
    """The run ended well on all three robots (each said ``end``), nobody was said lost, no
    process traced back."""
    print(result.text)
    assert result.code == 0, result.text
    assert result.text.count(end) == 3
    assert lost == {}
    assert team.tracebacks() == {}


async def through(fault: str | None, out: Path) -> tuple[float, bytes]:
    """Search and rescue at the control delay through ``fault`` (5 s, half a second into the
    run; ``"loss"``: LOSSY throughout; None: none): how long the run took, its recording."""
    plan = rescue()
    assert plan.world is not None
    plan = replace(plan, world=replace(plan.world, control_delay=CONTROL_DELAY))
    async with Netlab(HOSTS) as lab, TeamAcrossHosts(lab, plan, out=out, seed=SEED) as team:
        if fault == "loss":
            assert team.proxy is not None
            team.proxy.up = team.proxy.down = LOSSY
        timed = None if fault == "loss" else fault
        result = await team.run_with_fault(timed, at=0.5, timeout=150)
        lost = losses(result, team)  # before the stop, whose leaving the world logs
    completed(result, team, lost)
    waited = [line for _, line in result.lines if "waiting for" in line]
    if timed is not None:
        assert result.fault == f"{fault} 5 s at +0.5 s"
        assert len(waited) == 1 and "patience, 10 s" in waited[0]  # said once, while it lasted
    assert result.run_s is not None
    return result.run_s, team.recording.read_bytes()


@pytest.mark.timeout(420)
async def test_search_and_rescue_goes_through_a_partition_a_router_stall_and_loss(
    tmp_path: Path,
) -> None:
    clean, recorded = await through(None, tmp_path / "clean")
    partition, after_partition = await through("partition", tmp_path / "partition")
    stall, after_stall = await through("stall", tmp_path / "stall")
    lossy, after_loss = await through("loss", tmp_path / "loss")
    # lock-step with the same seed and control delay: the same run
    assert after_partition == recorded and after_stall == recorded and after_loss == recorded
    print(
        f"run: clean {clean:.1f} s, partition 5 s {partition:.1f} s, stall 5 s {stall:.1f} s, "
        f"10 % loss {lossy:.1f} s"
    )


def hello(plan: TeamPlan) -> TeamPlan:
    """The team of ``plan`` running hello_team (radio, calls, a collective; seconds long),
    listening 3 s for hellos: at 50 ± 20 ms each way and 2 % loss a hello crosses the link twice
    (robot, router, robot), after the team's start crossed it, and each loss holds a chunk 200 ms,
    then 400 ms more; half a second (its default) missed one in a CI run."""
    return replace(plan, program=ProgramPlan("hello_team", args={"listen": 3.0}, run="hello"))


@pytest.mark.timeout(240)
async def test_a_team_runs_to_its_end_at_a_2_percent_lossy_50ms_link(tmp_path: Path) -> None:
    """(10 % loss: search and rescue above, on the same link.)"""
    loss = 0.02
    async with (
        Netlab(HOSTS) as lab,
        TeamAcrossHosts(lab, hello(rescue()), out=tmp_path, seed=SEED) as team,
    ):
        assert team.proxy is not None
        team.proxy.up = team.proxy.down = Impairment(0.05, 0.02, loss=loss)
        result = await team.run_program(timeout=120)
        lost = losses(result, team)
        chunks_lost = team.proxy.stats.lost
    completed(result, team, lost, end='"team_size": 3')
    # range-limited broadcasts cross the router's ACL (cells: bcc/, their senders' tokens: bcl/)
    assert "ernst: heard who=['elvis', 'moseley']" in result.text  # 2 m either side, within 3 m
    assert "moseley: heard who=['ernst']" in result.text  # elvis is 4 m away
    print(f"loss {loss:.0%}: {chunks_lost} chunks retransmitted; run {result.run_s} s")


@pytest.mark.timeout(240)
async def test_processes_started_while_the_router_is_down_come_up_with_it(tmp_path: Path) -> None:
    async with (
        Netlab(HOSTS) as lab,
        TeamAcrossHosts(lab, rescue(), out=tmp_path, seed=SEED, router_first=False) as team,
    ):
        tool = {**team.env(WORKSTATION), "MOVER_PATIENCE": "1"}
        t0 = time.monotonic()
        code, said = await lab.run("c", sys.executable, "-m", "mover._cli", "ps", env=tool)
        print(said)
        assert code != 0 and time.monotonic() - t0 < 15
        assert "Traceback" not in said
        assert re.search(r"mover ps: cannot reach tls/\S+ within 1 s", said)
        run = asyncio.ensure_future(team.run_program(timeout=120))  # mover run, router down too
        await asyncio.sleep(3.0)
        await team.start_router()
        result = await run
        lost = losses(result, team)
    completed(result, team, lost)
    for name in ("world", "elvis", "ernst", "moseley"):
        log = (tmp_path / f"{name}.log").read_text()
        assert log.count("cannot reach tls/") == 1, log  # one line, however long it waits
        assert log.count("reached tls/") == 1, log
    assert last_tick(team.recording) is not None


@pytest.mark.timeout(180)
async def test_a_killed_robot_is_reported_at_once(tmp_path: Path) -> None:
    async with (
        Netlab(HOSTS) as lab,
        TeamAcrossHosts(lab, rescue(), out=tmp_path, seed=SEED) as team,
    ):
        run = asyncio.ensure_future(team.run_program(timeout=120))
        await asyncio.wait_for(team.run_started.wait(), 60)
        await asyncio.sleep(1.0)
        killed = time.monotonic()
        team.members[0].signal(
            signal.SIGKILL
        )  # elvis: its socket closes, the router sees it at once
        result = await run
        ended = time.monotonic() - killed
    print(result.text)
    print(f"mover run ended {ended:.1f} s after the SIGKILL")
    assert result.code == 1
    assert re.search(r"FAILED .*elvis", result.text)
    assert ended < 5.0  # the patience (10 s) is for members that may come back, not the dead
    assert team.tracebacks() == {}
