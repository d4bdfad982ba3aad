"""mover's pytest plugin, as a user's test suite sees it: a pytest run in a subprocess on test
files that use its fixtures with real processes (world, robots, launcher)."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.processes

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[2]

HELLO = """
import time
from mover import launch

ROBOTS = ["elvis", "ernst", "moseley"]

async def test_hello(mover_world, mover_robots, mover_launcher):
    t0 = time.monotonic()
    await mover_world("worlds/search_and_rescue.toml", expect=3)
    await mover_robots(*ROBOTS)
    for name in ROBOTS:  # their procedures are exported once mover_robots returns
        pose = await mover_launcher.call(name, "robot.pose", timeout=5)
        assert len(pose) == 3, pose
    outcomes = await launch(mover_launcher, "hello_team", ROBOTS, {}, run="t1")
    assert all("result" in o for o in outcomes.values()), outcomes
    print(f"TOOK {time.monotonic() - t0:.1f} s")
"""

DIES = """
import asyncio, os, signal
from mover import launch

async def test_a_robot_dies(mover_world, mover_robots, mover_launcher):
    await mover_world("worlds/search_and_rescue.toml", expect=1)
    (robot,) = await mover_robots("ernst")
    os.kill(robot.pid, signal.SIGKILL)  # not the test's doing, as far as the plugin knows
    await asyncio.sleep(60)

async def test_a_robot_that_never_starts(mover_robots):
    await mover_robots("bad name/*")

async def test_a_world_that_exits_early(mover_world):
    await mover_world("worlds/broken.toml")
"""

HANGS = """
import asyncio, os
from pathlib import Path

async def test_hangs(mover_world, mover_robots):
    await mover_world("worlds/search_and_rescue.toml", expect=1)
    (robot,) = await mover_robots("ernst")
    Path(os.environ["PIDS_FILE"]).write_text(str(robot.pid))
    await asyncio.sleep(120)
"""


UP = """
from mover import launch

async def test_a_team_file(mover_up):
    team = await mover_up("team.toml")
    assert (team.out / "world.log").exists()
    outcomes = await launch(team.node, "hello_team", ["ernst", "moseley"], {}, run="t1")
    assert all("result" in o for o in outcomes.values()), outcomes
"""

TEAM = """
[team]
name = "plugin"

[world]
file = "worlds/search_and_rescue.toml"
expect = 2

[[robots]]
names = ["ernst", "moseley"]
"""


def test_a_team_file_comes_up_for_a_test(pytester: pytest.Pytester) -> None:
    _suite(pytester, test_up=UP)
    (pytester.path / "team.toml").write_text(TEAM)
    result = pytester.runpytest_subprocess("-q", "-p", "no:cacheprovider", timeout=120)
    result.assert_outcomes(passed=1)


def _suite(pytester: pytest.Pytester, **files: str) -> None:
    pytester.makeini(
        "[pytest]\nasyncio_mode = auto\nasyncio_default_fixture_loop_scope = function\n"
    )
    (pytester.path / "worlds").mkdir()
    shutil.copy(ROOT / "worlds" / "search_and_rescue.toml", pytester.path / "worlds")
    (pytester.path / "worlds" / "broken.toml").write_text('[world]\nsize = [10, "x"]\n')
    pytester.makepyfile(**files)


def test_a_user_test_runs_a_program_on_real_processes(pytester: pytest.Pytester) -> None:
    """Three robots and a lock-step world, ready by membership, a program run: the issue asks
    for under 10 s; the bound here is looser so that a loaded machine does not fail it."""
    _suite(pytester, test_team=HELLO)
    result = pytester.runpytest_subprocess("-q", "-s", "-p", "no:cacheprovider", timeout=120)
    result.assert_outcomes(passed=1)
    took = [float(line.split()[1]) for line in result.outlines if line.startswith("TOOK")]
    print(f"a 3-robot lock-step program through the plugin: {took[0] if took else None} s")
    assert took and took[0] < 30.0, result.outlines


def test_an_exit_fails_the_test_at_once_with_the_logs(pytester: pytest.Pytester) -> None:
    _suite(pytester, test_dies=DIES)
    t0 = time.monotonic()
    result = pytester.runpytest_subprocess("-q", "-p", "no:cacheprovider", timeout=120)
    assert time.monotonic() - t0 < 50  # not the 60 s the first test would sleep
    result.assert_outcomes(failed=3)
    text = result.stdout.str()
    assert "ernst exited with code -9 while the test ran: the test was stopped there" in text
    assert "mover log: ernst" in text  # the robot's log, attached
    assert "bad name/* exited with code" in text and "before bad name/* were ready" in text
    # the world that rejected its file: its own words, from its log, in the failure
    assert "before world were ready" in text and "size" in text


def test_no_process_outlives_a_killed_pytest(pytester: pytest.Pytester, tmp_path: Path) -> None:
    _suite(pytester, test_hangs=HANGS)
    pids = tmp_path / "pids"
    env = {**os.environ, "PIDS_FILE": str(pids)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_hangs.py"],
        cwd=pytester.path,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 60
        while not pids.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert pids.exists(), "the robot never started"
        robot = int(pids.read_text())
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
        deadline = time.monotonic() + 10
        while _alive(robot) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _alive(robot), "the robot outlived pytest"
    finally:
        if proc.poll() is None:
            proc.kill()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    stat = Path(f"/proc/{pid}/stat")
    return stat.exists() and stat.read_text().split()[2] != "Z"
