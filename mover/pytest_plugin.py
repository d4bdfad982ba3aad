"""mover's pytest plugin: fixtures for multi-process tests of team programs.

Installing mover enables it (the ``pytest11`` entry point). Its fixtures are pytest-asyncio
fixtures: set ``asyncio_mode = "auto"`` in your pytest settings (or mark each test with
``@pytest.mark.asyncio``) — that is the one step to take first::

    from mover import launch

    async def test_hello_team(mover_world, mover_robots, mover_launcher):
        await mover_world("worlds/search_and_rescue.toml", expect=2)  # relative to this file
        await mover_robots("ernst", "moseley")
        outcomes = await launch(mover_launcher, "hello_team", ["ernst", "moseley"], {}, run="t1")
        assert all("result" in o for o in outcomes.values())

Fixtures:

* ``mover_team`` — a fresh team (its own name and key);
* ``mover_cluster`` — a :class:`~mover.testing.Cluster` of that team on a seed port chosen at
  run time, whose processes start in the test file's directory and log to files;
* ``mover_launcher`` — the test's own node, a member listening on the seed port;
* ``mover_world(file, *args, expect=0, name="world")`` — a lock-step world process, ready
  once it is a member of the team;
* ``mover_robots(*names, hardware="sim")`` — robot processes, ready once they are members;
* ``mover_member(module, name, *args)`` — ``python -m module name args`` (e.g. a module that
  runs :func:`~mover.testing.serve_programs`), ready once ``name`` is a member;
* ``mover_up(team_file, *args)`` — ``mover up`` of a team file (relative to the test file)
  with a fresh key, ready once it says so (by membership); returns an :class:`UpTeam` whose
  ``node`` is a member of that team (launch programs with it) and ``out`` its run folder;
  stopped with Ctrl-C at the end, its processes' logs in a failed test's report.

What they promise: readiness is membership, never a sleep; a process that exits before it is
ready fails the test at once with the end of its log, and so does one that exits while the test
runs (unless the test ended it with :meth:`Cluster.kill`); every process's log is attached to a
failed test's report; every process dies with the test run, even when pytest is SIGKILLed
(Linux: a parent-death signal).
"""

from __future__ import annotations

import asyncio
import os
import re
import secrets
import signal
import sys
from collections.abc import AsyncIterator, Awaitable, Callable, Generator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio

from ._config import NodeConfig, TeamCredentials
from ._futures import failure
from ._node import Node
from ._procs import Child
from ._procs import start as start_process
from ._procs import stop as stop_processes
from .testing import Cluster, cluster, first_line

READY_TIMEOUT = 60.0
"""Seconds a process may take to become a member."""
LOG_TAIL = 60
"""Lines of each process's log put into a failed test's report."""

_CLUSTER = pytest.StashKey[Cluster]()
_UP_LOGS = pytest.StashKey[list[Path]]()
_READY = re.compile(r"ready in .*MOVER_TEAM=(\S+) MOVER_CONNECT=(\S+)")
_CALL_FAILED = pytest.StashKey[bool]()


@pytest.fixture
def mover_team() -> TeamCredentials:
    """A fresh team: its own name and key."""
    return TeamCredentials.generate(f"test-{secrets.token_hex(3)}")


@pytest_asyncio.fixture
async def mover_cluster(
    request: pytest.FixtureRequest, mover_team: TeamCredentials, tmp_path: Path
) -> AsyncIterator[Cluster]:
    """The test's processes: started in the test file's directory, logging to files, all
    killed at the end; one that exits on its own while the test runs fails the test."""
    async with cluster(mover_team, cwd=request.path.parent, logs=tmp_path / "mover-logs") as c:
        request.node.stash[_CLUSTER] = c
        watch = asyncio.get_running_loop().create_task(_watch(c, _test_task(request)))
        try:
            yield c
        finally:
            watch.cancel()
            await asyncio.gather(watch, return_exceptions=True)
        exited = c.exited()
    if exited and not request.node.stash.get(_CALL_FAILED, False):
        why = f"{exited[0].brief} while the test ran (its log is in the report)"
        pytest.fail(why, pytrace=False)


@pytest_asyncio.fixture
async def mover_launcher(mover_cluster: Cluster) -> AsyncIterator[Node]:
    """The test's own node: a member of the team, listening on the seed port."""
    async with mover_cluster.launcher() as node:
        yield node


Starter = Callable[..., Awaitable[Any]]


@pytest_asyncio.fixture
async def mover_world(mover_cluster: Cluster, mover_launcher: Node) -> Starter:
    """``await mover_world(file, *args, expect=0, name="world")``: a lock-step world."""

    async def start(
        worldfile: str, *args: str, expect: int = 0, name: str = "world"
    ) -> asyncio.subprocess.Process:
        proc = await mover_cluster.world(worldfile, "--name", name, *args, expect=expect)
        await _ready(mover_cluster, mover_launcher, [name])
        return proc

    return start


@pytest_asyncio.fixture
async def mover_robots(mover_cluster: Cluster, mover_launcher: Node) -> Starter:
    """``await mover_robots(*names, hardware="sim")``: robot processes (``python -m robots``),
    returned once each is up with its hardware and its ``robot.*`` procedures exported. A
    lock-step world starts when all the robots it expects are in: start them in one call."""

    async def start(*names: str, hardware: str = "sim") -> list[asyncio.subprocess.Process]:
        procs = [
            await mover_cluster.start(
                "robots", "--name", n, "--hardware", hardware, ready=None, label=n
            )
            for n in names
        ]
        await _ready(mover_cluster, mover_launcher, list(names), said_ready=procs)
        return procs

    return start


@pytest_asyncio.fixture
async def mover_member(mover_cluster: Cluster, mover_launcher: Node) -> Starter:
    """``await mover_member(module, name, *args)``: ``python -m module name args``."""

    async def start(module: str, name: str, *args: str) -> asyncio.subprocess.Process:
        proc = await mover_cluster.start(module, name, *args, ready=None, label=name)
        await _ready(mover_cluster, mover_launcher, [name])
        return proc

    return start


@dataclass
class UpTeam:
    """A team ``mover up`` started: a member node of the test's in it, the run folder, and
    what ``mover up`` printed so far."""

    node: Node
    out: Path
    lines: list[str]
    proc: asyncio.subprocess.Process


@pytest_asyncio.fixture
async def mover_up(request: pytest.FixtureRequest, tmp_path: Path) -> AsyncIterator[Starter]:
    """``await mover_up(team_file, *args)``: a team from a team file, ready (see the module)."""
    started: list[tuple[Child, Node]] = []
    logs = request.node.stash.setdefault(_UP_LOGS, [])

    async def start(team_file: str, *args: str) -> UpTeam:
        out = tmp_path / f"up-{len(started)}"
        logs.append(out)
        key = secrets.token_bytes(32)
        env = {**os.environ, "MOVER_TEAM_KEY": key.hex()}
        env.pop("MOVER_TEAM_KEY_FILE", None)
        argv = [sys.executable, "-m", "mover", "up", team_file, "--out", str(out), *args]
        child = await start_process(
            f"mover up {team_file}", argv, env=env, log=None, pump=True,
            cwd=request.path.parent, own_session=True,
        )  # fmt: skip
        proc = child.proc
        lines: list[str] = []
        assert proc.stdout is not None
        try:
            async with asyncio.timeout(READY_TIMEOUT):
                while (ready := _READY.search(lines[-1] if lines else "")) is None:
                    line = (await proc.stdout.readline()).decode(errors="replace")
                    if not line:
                        tail = "\n".join(lines[-LOG_TAIL:])
                        pytest.fail(f"mover up {team_file} exited before it was ready:\n{tail}")
                    lines.append(line.rstrip())
        except TimeoutError:
            proc.kill()
            pytest.fail(f"mover up {team_file} was not ready within {READY_TIMEOUT:g} s")
        name, endpoint = ready.group(1), ready.group(2)
        router = any("router on" in line for line in lines)
        config = NodeConfig(mode="client" if router else "peer", connect=(endpoint,))
        node = Node(
            f"test-{secrets.token_hex(2)}", TeamCredentials(name, key), kind="tool", config=config
        )
        await node.__aenter__()
        started.append((child, node))
        # ready by membership here too: every process mover up started (a log each; the
        # router is no member) is seen by the test's node before the test goes on
        names = [p.stem for p in out.glob("*.log") if p.stem != "router"]
        try:
            await node.membership.wait_for(names, timeout=READY_TIMEOUT)
        except TimeoutError:
            missing = [n for n in names if n not in node.membership]
            pytest.fail(f"{', '.join(missing)} of {team_file} not seen within {READY_TIMEOUT:g} s")
        return UpTeam(node, out, lines, proc)

    try:
        yield start
    finally:
        for child, node in started:
            await node.__aexit__(None, None, None)
            await stop_processes([child], [(signal.SIGINT, 20.0), (signal.SIGKILL, 20.0)])


async def _ready(
    c: Cluster,
    node: Node,
    names: Sequence[str],
    said_ready: Sequence[asyncio.subprocess.Process] = (),
) -> None:
    """Wait until ``names`` are members, and each of ``said_ready`` printed READY (a robot
    process does once its hardware is up and its procedures are exported: a test's first
    ``robot.*`` call finds them); fail at once if one of the processes exits first."""

    async def up() -> None:
        async with asyncio.timeout(READY_TIMEOUT):
            await node.membership.wait_for(list(names), timeout=READY_TIMEOUT)
            ready = (
                first_line(p, lambda line: line.startswith("READY"), READY_TIMEOUT)
                for p in said_ready
            )
            await asyncio.gather(*ready)

    waiting = asyncio.ensure_future(up())
    died = asyncio.ensure_future(c.first_exit())
    try:
        done, _ = await asyncio.wait({waiting, died}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for f in (waiting, died):
            f.cancel()
        await asyncio.gather(waiting, died, return_exceptions=True)
    if died in done and not died.cancelled() and failure(died) is None:
        exit_ = died.result()
        c.claimed.add(exit_.label)  # reported here: the watcher leaves the test alone
        why = f"{exit_.brief} before {', '.join(names)} were ready:\n{exit_.tail}"
        pytest.fail(why, pytrace=False)
    if waiting in done and failure(waiting) is not None:
        missing = [n for n in names if n not in node.membership]
        what = "become members" if missing else "say READY (their hardware up)"
        pytest.fail(
            f"{', '.join(missing or names)} did not {what} within {READY_TIMEOUT:g} s",
            pytrace=False,
        )


def _test_task(request: pytest.FixtureRequest) -> Callable[[], asyncio.Task[Any] | None]:
    """Finds the task running the test's body (once it runs), to cancel it on an exit."""
    name = request.function.__name__

    def find() -> asyncio.Task[Any] | None:
        for task in asyncio.all_tasks():
            coro = task.get_coro()
            if getattr(coro, "__name__", None) == name or name in getattr(coro, "__qualname__", ""):
                return task
        return None

    return find


async def _watch(c: Cluster, test: Callable[[], asyncio.Task[Any] | None]) -> None:
    """When a process exits on its own while the test runs, cancel the test at once."""
    exit_ = await c.first_exit()
    await asyncio.sleep(0.1)  # a process that dies while it starts is reported by _ready
    task = test()
    if exit_.label not in c.claimed and task is not None and not task.done():
        task.cancel(exit_.brief)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    """A failed test's report gets the end of every process's log."""
    report = yield
    if report.failed:
        for out in item.stash.get(_UP_LOGS, []):
            for path in sorted(out.glob("*.log")):
                lines = path.read_text(errors="replace").splitlines()
                report.sections.append((f"mover up log: {path.stem}", "\n".join(lines[-LOG_TAIL:])))
    c = item.stash.get(_CLUSTER, None)
    if report.when == "call":
        item.stash[_CALL_FAILED] = report.failed
    if c is not None and report.failed:
        exits = c.exited()
        if (
            exits
            and call.excinfo is not None
            and call.excinfo.errisinstance(asyncio.CancelledError)
        ):
            report.longrepr = f"{exits[0].brief} while the test ran: the test was stopped there"
        for label, path in c.logs_written():
            try:
                lines = path.read_text(errors="replace").splitlines()
            except OSError:
                continue
            report.sections.append((f"mover log: {label}", "\n".join(lines[-LOG_TAIL:])))
        for exit_ in c.exited():
            report.sections.append(("mover: a process exited", exit_.brief))
    return report
