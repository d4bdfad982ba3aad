"""Ctrl-C (SIGINT) and SIGTERM of each process kind mid-run: a prompt, quiet, clean exit.

Real processes over zenoh on 127.0.0.1: a lock-step world (``mover world --lockstep``) with
robot processes (``mover robot``) in a run started by a launcher (``mover run``, not detached);
a grid world (``mover gridworld``) in a foraging run; a router (``mover router``) with members
behind it; ``mover demo``. Each one is interrupted while the run is under way and must exit
within ``BOUND`` seconds with a clean status — 130 after Ctrl-C (``mover``'s status for an
interrupt, ``mover/cli/_main.py``), 0 where the process treats the signal as its ordinary stop (the
router), 143, 130 or 0 after SIGTERM — writing no traceback to its output or its log, and at most
``QUIET`` lines after the signal. A robot that is interrupted is seen leaving by the others,
and the run fails on the rest with MemberLost.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio

from mover import Node, NodeConfig
from mover._config import free_port
from sim_hw.grid import place_resources, random_obstacles
from tests.helpers.procs import ROOT, Cluster, cluster
from tests.programs._grid import WORLD as GRID_WORLD
from tests.programs._grid import start_robots, write_grid

WORLD = "worlds/search_and_rescue.toml"
ROBOTS = ["elvis", "ernst", "moseley"]
BOUND = 10.0  # seconds from the signal to the exit
QUIET = 3  # lines a process may write after the signal (a goodbye, a log line or two)
INTERRUPTED = {signal.SIGINT: (130, 0), signal.SIGTERM: (143, 130, 0)}

pytestmark = [pytest.mark.processes, pytest.mark.timeout(180)]


@dataclass
class Exit:
    """How a process took a signal: its status, how long it took, what it wrote after."""

    sig: signal.Signals
    status: int | None
    took: float
    said: str  # standard error and log, after the signal
    everything: str  # all output and the whole log

    def check(self) -> None:
        """Assert a prompt, clean, quiet exit with no traceback."""
        assert self.took < BOUND, f"still running {BOUND} s after {self.sig.name}"
        assert "Traceback" not in self.everything, self.everything[-4000:]
        assert "Task exception was never retrieved" not in self.everything, self.everything
        assert self.status in INTERRUPTED[self.sig], (
            f"status {self.status} after {self.sig.name}: {self.said}"
        )
        assert len(self.said.splitlines()) <= QUIET, self.said


async def stop(
    proc: asyncio.subprocess.Process, sig: signal.Signals, log: Path | None = None
) -> Exit:
    """Send ``sig`` to ``proc`` and wait (at most BOUND s) for it to exit."""
    before = log.stat().st_size if log is not None and log.exists() else 0
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        out, err = await asyncio.wait_for(proc.communicate(), BOUND)
    except TimeoutError:
        proc.kill()
        out, err = await proc.communicate()
    took = time.monotonic() - t0
    whole = log.read_bytes() if log is not None else b""
    said = whole[before:] + (err or b"")
    return Exit(
        sig,
        proc.returncode,
        took,
        said.decode(errors="replace"),
        (whole + (out or b"") + (err or b"")).decode(errors="replace"),
    )


async def mover(c: Cluster, log: Path, *args: str, ready: str | None = "READY") -> Any:
    """``mover ARGS`` as a process of the cluster, its standard error in ``log``."""
    return await c.start("mover._cli", *args, ready=ready, log=log, timeout=40.0)


async def until(predicate: Any, timeout: float, what: str) -> None:
    """Wait (bounded) until ``await predicate()`` is true."""
    try:
        async with asyncio.timeout(timeout):
            while not await predicate():
                await asyncio.sleep(0.05)
    except TimeoutError:
        pytest.fail(f"not {what} within {timeout} s")


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def interrupted_run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A lock-step world, three robots in a run started by ``mover run``; the launcher
    interrupted mid-run, then the robot elvis; what each did and what the others' runs say."""
    tmp = tmp_path_factory.mktemp("ctrl_c")
    found: dict[str, Any] = {}
    async with cluster() as c, c.launcher() as node:
        await mover(c, tmp / "world.log", "world", WORLD, "--lockstep", "--expect", "3")
        # together: each says READY once in the world, and the world starts with all three
        started = [mover(c, tmp / f"{name}.log", "robot", "--name", name) for name in ROBOTS]
        robots = dict(zip(ROBOTS, await asyncio.gather(*started), strict=True))
        await node.membership.wait_for(["world", *ROBOTS], timeout=30)
        run = "sr"
        launcher = await mover(
            c,
            tmp / "run.log",
            "run",
            "search_and_rescue",
            "--robots",
            ",".join(ROBOTS),
            "--run-id",
            run,
            ready=f"run {run}:",
        )
        outcomes = {
            m: asyncio.ensure_future(node.call(m, "mover.outcome", run, timeout=None))
            for m in ROBOTS
        }

        async def ticking() -> bool:  # the run is under way: the world ticks for it
            return bool((await node.call("world", "status", timeout=5))["tick"] > 10)

        await until(ticking, 30, "ticking")
        found["launcher"] = await stop(launcher, signal.SIGINT, tmp / "run.log")
        found["run went on"] = not any(o.done() for o in outcomes.values())
        found["elvis"] = await stop(robots["elvis"], signal.SIGINT, tmp / "elvis.log")
        try:
            await node.membership.wait_gone("elvis", timeout=5)
            found["seen leaving"] = True
        except TimeoutError:
            found["seen leaving"] = False
        rest = ("ernst", "moseley")
        ends = await asyncio.wait_for(asyncio.gather(*(outcomes[m] for m in rest)), 30)
        found["outcomes"] = dict(zip(rest, ends, strict=True))
        outcomes["elvis"].cancel()
        await asyncio.gather(outcomes["elvis"], return_exceptions=True)
    return found


@pytest.mark.asyncio(loop_scope="module")
async def test_ctrl_c_of_the_launcher_mid_run(interrupted_run: dict[str, Any]) -> None:
    """``mover run`` goes quietly, and the run goes on without it (it is no coordinator)."""
    interrupted_run["launcher"].check()
    assert interrupted_run["run went on"]


@pytest.mark.asyncio(loop_scope="module")
async def test_ctrl_c_of_a_robot_mid_run(interrupted_run: dict[str, Any]) -> None:
    """The robot goes quietly, the others see it leave and their run fails."""
    interrupted_run["elvis"].check()
    assert interrupted_run["seen leaving"]
    for end in interrupted_run["outcomes"].values():
        assert "error" in end, interrupted_run["outcomes"]


@pytest.mark.asyncio(loop_scope="module")
async def test_a_robot_interrupted_mid_run_fails_the_run_with_member_lost(
    interrupted_run: dict[str, Any],
) -> None:
    for end in interrupted_run["outcomes"].values():
        assert "MemberLost" in end.get("error", ""), interrupted_run["outcomes"]


async def test_sigterm_of_a_robot_is_a_clean_stop(tmp_path: Path) -> None:
    async with cluster() as c, c.launcher() as node:
        log = tmp_path / "r1.log"
        robot = await mover(c, log, "robot", "--name", "r1", "--hardware", "none")
        await node.membership.wait_for(["r1"], timeout=20)
        (await stop(robot, signal.SIGTERM, log)).check()
        await node.membership.wait_gone("r1", timeout=5)


async def test_ctrl_c_of_a_lock_step_world_mid_run(tmp_path: Path) -> None:
    async with cluster() as c, c.launcher() as node:
        log = tmp_path / "world.log"
        world = await mover(c, log, "world", WORLD, "--lockstep", "--expect", "2")
        await asyncio.gather(
            *(mover(c, tmp_path / f"{name}.log", "robot", "--name", name) for name in ROBOTS[1:])
        )
        await node.membership.wait_for(["world", *ROBOTS[1:]], timeout=30)
        for m in ROBOTS[1:]:
            await node.call(m, "mover.start", "search_and_rescue", "sr", ROBOTS[1:], {}, timeout=10)

        async def ticking() -> bool:
            return bool((await node.call("world", "status", timeout=5))["tick"] > 10)

        await until(ticking, 30, "ticking")
        (await stop(world, signal.SIGINT, log)).check()
        await node.membership.wait_gone("world", timeout=5)


async def test_ctrl_c_of_a_grid_world_mid_run(tmp_path: Path) -> None:
    base = (7, 7)
    grid = random_obstacles(15, 15, 0.05, 11, keep_free=(base,))
    resources = place_resources(grid, 2, 1000, 12, exclude=(base,), reachable_from=base)
    field = write_grid(tmp_path / "field.json", grid.obstacles, base, resources)
    names = ["k0", "k1"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        log = tmp_path / "gridworld.log"
        world = await mover(c, log, "gridworld", str(field), "--expect", "2")
        await start_robots(c, names, [{"view": 0}] * 2)
        await node.membership.wait_for([GRID_WORLD, *names], timeout=20)
        for m in names:
            await node.call(m, "mover.start", "foraging", "forage", names, {"seed": 5}, timeout=10)

        async def moving() -> bool:
            state = await node.call(GRID_WORLD, "state", timeout=5)
            return bool(state["moves"].get("k1", 0) >= 5)

        await until(moving, 30, "moving")
        (await stop(world, signal.SIGINT, log)).check()
        await node.membership.wait_gone(GRID_WORLD, timeout=5)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
async def test_ctrl_c_of_a_router_with_members_behind_it(
    tmp_path: Path, sig: signal.Signals
) -> None:
    port = free_port()
    behind = NodeConfig(mode="client", listen=(), connect=(f"tcp/127.0.0.1:{port}",))
    async with cluster() as c:
        log = tmp_path / "router.log"
        router = await mover(c, log, "router", "--listen", f"tcp/127.0.0.1:{port}", ready="router")
        for name in ("r1", "r2"):
            await c.start(
                "mover._cli", "robot", "--name", name, "--hardware", "none", config=behind
            )
        async with Node("tester", c.team, kind="tool", config=behind) as node:
            await node.membership.wait_for(["r1", "r2"], timeout=20)
            assert await node.call("r1", "mover.programs", timeout=5) is not None
            (await stop(router, sig, log)).check()
            await node.membership.wait_gone("r1", timeout=10)  # the link to the others went with it


async def test_ctrl_c_of_mover_demo_mid_run(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", "demo", "--out", str(out), "--timeout", "120",
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    assert proc.stdout is not None
    seen: list[str] = []
    try:
        async with asyncio.timeout(60):  # until the program runs: a progress line
            while not any("searching" in line for line in seen):
                line = (await proc.stdout.readline()).decode()
                assert line, f"the demo ended before its run: {''.join(seen)}"
                seen.append(line)
    except BaseException:
        proc.kill()
        await proc.wait()
        raise
    (await stop(proc, signal.SIGINT)).check()
    logs = {p.name: p.read_text(errors="replace") for p in out.rglob("*.log")}
    assert logs, "the demo kept no logs"
    for name, text in logs.items():
        assert "Traceback" not in text, f"{name}:\n{text[-3000:]}"
    await asyncio.sleep(0.5)
    left = _running_with(str(out))
    assert not left, f"left running: {left}"


def _running_with(*words: str) -> list[str]:
    """Command lines of running processes that contain every one of ``words``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        line = " ".join(a.decode(errors="replace") for a in argv)
        if all(w in line for w in words) and str(os.getpid()) != entry.name:
            found.append(line)
    return found
