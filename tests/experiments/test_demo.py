"""`mover demo` end to end: a world process, robot processes, a program, a report and a PNG."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from experiments.demo_runs import first_difference, report, run_demo
from mover.testing import cpu_hogs
from tests.helpers.procs import ROOT

pytestmark = pytest.mark.processes


async def test_hello_team_demo_runs_on_processes(tmp_path: Path) -> None:
    world = str(ROOT / "worlds" / "search_and_rescue.toml")
    code, out = await run_demo(tmp_path, "--program", "hello_team", "--world", world)
    assert code == 0, out
    assert "ernst: heard who=[elvis, moseley]" in out  # 2 m either side, within its 3 m
    assert "moseley: heard who=[ernst]" in out  # elvis is 4 m away
    assert "step 1 (and): 4 messages for 3 members (bound 4)" in out
    assert (tmp_path / "trajectories.png").stat().st_size > 1000


async def test_search_and_rescue_with_three_robot_processes_moves_the_box(tmp_path: Path) -> None:
    """The README's first command (seed 1): world + 3 robot processes + the program, end to
    end. Runs repeat now, so a seed gives one outcome: seed 2's find comes at 20 s and its
    push veers off the path (0.76 m nearer the goal); seeds 1, 3, 4, 5 bring it 2.75-2.98 m."""
    code, out = await run_demo(tmp_path)
    assert code == 0, out
    assert out.count(": done") == 3, out
    step = r"step (\d+) \((\w+)\): (\d+) messages for \d+ members \(bound (\d+)\)"
    steps = re.findall(step, out)
    assert steps, out
    over = [f"step {n} ({kind}): {m} > {b}" for n, kind, m, b in steps if int(m) > int(b)]
    assert not over, (over, out)  # each step within its message bound (issue 28: 14 > 12)
    moved = [line for line in out.splitlines() if line.startswith("box 'victim' moved")]
    assert moved, out
    nearer = float(moved[0].split("; ")[1].split(" m nearer")[0])
    print(moved[0])
    assert nearer >= 2.0  # the box went at least 2 m along its path, toward the goal
    winners = {
        line.split('"winner": "')[1].split('"')[0]
        for line in out.splitlines()
        if '"winner": "' in line
    }
    assert len(winners) == 1  # every member agreed on the finder
    assert (tmp_path / "trajectories.png").stat().st_size > 1000


@pytest.mark.slow
async def test_the_demo_fails_fast_when_its_world_is_killed() -> None:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", "demo", cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT,
    )  # fmt: skip
    assert proc.stdout is not None
    async with asyncio.timeout(60):
        while b"processes up" not in await proc.stdout.readline():
            pass
    await asyncio.sleep(1.0)
    worlds = subprocess.run(  # noqa: ASYNC221  (a moment's pgrep)
        ["pgrep", "-P", str(proc.pid), "-f", "mover._cli world"], capture_output=True, text=True
    )
    assert worlds.stdout.split(), "no world process of the demo's found"
    for pid in worlds.stdout.split():
        os.kill(int(pid), signal.SIGKILL)
    killed = time.monotonic()
    rest = (await asyncio.wait_for(proc.stdout.read(), 30)).decode()
    await proc.wait()
    assert proc.returncode == 1
    assert time.monotonic() - killed < 10
    assert "the world process was killed by signal 9" in rest
    assert "Traceback" not in rest


async def test_the_demo_fails_fast_with_the_worlds_error_when_it_rejects_its_file(
    tmp_path: Path,
) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[world]\nname = "huge"\nsize = [1e7, 1e7]\n[[robots]]\nid = "r1"\n')
    t0 = time.monotonic()
    code, out = await run_demo(tmp_path, "--world", str(bad))
    assert time.monotonic() - t0 < 5, out
    assert code == 2, out
    assert f"mover demo: world file {bad}:3: world.size: must be a list of 2 numbers" in out
    assert "each > 0 and at most 1000, got [10000000.0, 10000000.0]" in out
    assert "Traceback" not in out


@pytest.mark.slow
@pytest.mark.timeout(600)  # three runs of at most 150 + 30 s each (run_demo ends a stuck one)
async def test_one_seed_gives_one_recording_on_a_quiet_and_a_loaded_machine(
    tmp_path: Path,
) -> None:
    """Seed 7 (it parted under load before the fix of issue 22): once on a quiet machine, then
    twice beside two CPU hogs with the demo's processes SIGSTOPped for moments of up to 0.3 s:
    the same recording, byte for byte, and the same report."""
    reports, recordings = [], []
    for i in range(3):
        # each run bounded well inside the test's limit, so that one that hangs fails with the
        # demo's own output; each run's wall time printed (a CI run once spent the whole limit)
        started = time.monotonic()
        if i == 0:
            code, out = await run_demo(tmp_path / "0", "--seed", "7", timeout=150)
        else:
            with cpu_hogs(2):
                code, out = await run_demo(
                    tmp_path / str(i), "--seed", "7", stall_seed=i, timeout=150
                )
        print(f"run {i}: {time.monotonic() - started:.1f} s")
        assert code == 0, out
        reports.append(report(out))
        recordings.append((tmp_path / str(i) / "world.jsonl").read_bytes())
    print("\n".join(reports[0]))
    assert any(line.startswith("box 'victim' moved") for line in reports[0])
    first = tmp_path / "0" / "world.jsonl"
    for i in (1, 2):
        if recordings[i] != recordings[0]:  # say where the runs parted, then fail
            print(f"run {i} against run 0:")
            print(first_difference(first, tmp_path / str(i) / "world.jsonl"))
        assert recordings[i] == recordings[0]
        assert reports[i] == reports[0]
