"""Multi-process integration tests of team programs: real processes, real zenoh on 127.0.0.1.

::

    from mover.testing import cluster

    async def test_my_program():
        async with cluster() as c, c.launcher() as node:
            await c.world("worlds/search_and_rescue.toml", expect=2)
            await c.robots("ernst", "moseley")
            outcomes = await launch(node, "my_program", ["ernst", "moseley"], {}, run="t1")

:func:`cpu_hogs` and :func:`stutter` load the machine and stall a run's processes for moments,
for tests that a seeded run repeats however it is scheduled.

Across hosts (Linux, root): :class:`Netlab` makes hosts of network namespaces on one bridge
(partitions: a host's cable pulled), :class:`ImpairProxy` a bad link in user space (delay,
jitter, late "lost" chunks, stalls), and :class:`TeamAcrossHosts` a team file's team on them,
every process a client of an mTLS router; :func:`netlab_unavailable` says why not here::

    async with Netlab(("a", "b", "c")) as lab, TeamAcrossHosts(lab, load_team(f), out=d) as team:
        team.proxy.down = Impairment(0.05, 0.02, loss=0.1)
        result = await team.run_program(timeout=120)

Every process gets a fresh team key and connects to a seed port chosen at run time (multicast
scouting off); everything started is killed on exit, and dies with this process even when it is
SIGKILLed (Linux: a parent-death signal). ``pytest`` users get the same as fixtures from
:mod:`mover.pytest_plugin`.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from collections.abc import AsyncIterator, Callable, Mapping
from contextlib import asynccontextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._config import NodeConfig, TeamCredentials, free_port
from ._impair import Impairment, ImpairProxy
from ._load import cpu_hogs, descendants, stutter
from ._netlab import Netlab, NetlabError
from ._netlab import unavailable as netlab_unavailable
from ._netteam import TeamAcrossHosts
from ._node import Node
from ._procs import Child, ProcessExited, start, stop
from ._programs import ProgramHost

__all__ = [
    "Cluster",
    "ImpairProxy",
    "Impairment",
    "Netlab",
    "NetlabError",
    "ProcessExited",
    "TeamAcrossHosts",
    "cluster",
    "cpu_hogs",
    "descendants",
    "first_line",
    "free_port",
    "netlab_unavailable",
    "serve_programs",
    "stutter",
]

STOP_WAIT = 10.0
"""Seconds :meth:`Cluster.stop` waits for its killed processes."""


@dataclass
class Cluster:
    """A seed endpoint that every process connects to, and the processes started.

    With ``logs``, every process's standard error goes to ``<logs>/<label>.log``.
    """

    team: TeamCredentials
    port: int = field(default_factory=free_port)
    procs: list[asyncio.subprocess.Process] = field(default_factory=list)
    cwd: Path = field(default_factory=Path.cwd)
    env: dict[str, str] = field(default_factory=dict)
    logs: Path | None = None
    _children: dict[int, Child] = field(default_factory=dict)
    _ended: set[int] = field(default_factory=set)  # ended by the test or by stop()
    _exits: list[ProcessExited] = field(default_factory=list)
    _exit_seen: asyncio.Event | None = None
    _watchers: list[asyncio.Task[None]] = field(default_factory=list)
    claimed: set[str] = field(default_factory=set)
    """Labels of exits already reported (by the pytest plugin)."""

    @property
    def seed(self) -> NodeConfig:
        """Settings for the node that listens on the seed port (the test's own node)."""
        return NodeConfig(listen=(f"tcp/127.0.0.1:{self.port}",))

    @property
    def peer(self) -> NodeConfig:
        """Settings for every other node: a free port of its own, connecting to the seed."""
        return NodeConfig(connect=(f"tcp/127.0.0.1:{self.port}",))

    @asynccontextmanager
    async def launcher(self, name: str = "launcher") -> AsyncIterator[Node]:
        """The test's own node (a team member of kind ``tool``, listening on the seed port)."""
        async with Node(name, self.team, kind="tool", config=self.seed) as node:
            yield node

    async def start(
        self,
        module: str,
        *args: str,
        team: TeamCredentials | None = None,
        ready: str | None = "READY",
        timeout: float = 30.0,
        config: NodeConfig | None = None,
        log: str | os.PathLike[str] | None = None,
        label: str | None = None,
    ) -> asyncio.subprocess.Process:
        """Start ``python -m module args``; wait until it prints ``ready`` (None: no wait).

        ``log`` names a file for the process's standard error (its log lines); without it, a
        cluster with ``logs`` writes ``<logs>/<label>.log``, and otherwise it is this
        process's. ``label`` names the process in reports (default: module and arguments)."""
        label = label or " ".join([module, *args])[:60]
        if log is None and self.logs is not None:
            self.logs.mkdir(parents=True, exist_ok=True)
            log = self.logs / f"{_file_name(label)}.log"
        env = {**os.environ, **self.env, **(team or self.team).env(), **(config or self.peer).env()}
        err = open(log, "ab") if log is not None else None  # noqa: ASYNC230, SIM115
        child = await start(
            label,
            [sys.executable, "-m", module, *args],
            env=env,
            log=err,  # written by the child itself: kept even if this process is killed
            stdin=asyncio.subprocess.PIPE,  # serve_programs() runs until it closes
            cwd=self.cwd,
        )
        proc = child.proc
        self.procs.append(proc)
        self._children[proc.pid] = child
        self._watchers.append(asyncio.get_running_loop().create_task(self._watch(child)))
        if ready is None:
            return proc
        if await first_line(proc, lambda line: line.startswith(ready), timeout) is None:
            raise RuntimeError(f"{module} {' '.join(args)} exited before it was ready")
        return proc

    async def world(
        self, worldfile: str, *args: str, expect: int = 0
    ) -> asyncio.subprocess.Process:
        """Start a lock-step world process (``mover world``) expecting ``expect`` robots."""
        return await self.start(
            "mover",
            "world",
            worldfile,
            "--lockstep",
            "--expect",
            str(expect),
            *args,
            ready=None,
        )

    async def robots(self, *names: str, hardware: str = "sim") -> list[asyncio.subprocess.Process]:
        """Start robot processes (``python -m robots``) together and wait until all are up."""
        return list(
            await asyncio.gather(
                *(self.start("robots", "--name", n, "--hardware", hardware) for n in names)
            )
        )

    async def _watch(self, child: Child) -> None:
        code = await child.proc.wait()
        if child.proc.pid in self._ended:
            return
        self._exits.append(child.exited(code))
        self._exit_event().set()

    def _exit_event(self) -> asyncio.Event:
        if self._exit_seen is None:
            self._exit_seen = asyncio.Event()
        return self._exit_seen

    async def first_exit(self) -> ProcessExited:
        """Wait until a process exits on its own (not ended by :meth:`kill` or :meth:`stop`)."""
        await self._exit_event().wait()
        return self._exits[0]

    def exited(self) -> list[ProcessExited]:
        """The processes that exited on their own so far."""
        return list(self._exits)

    def logs_written(self) -> list[tuple[str, Path]]:
        """(label, log file) of every process that logs to a file."""
        return [(c.name, c.log) for c in self._children.values() if c.log is not None]

    def kill(self, proc: asyncio.subprocess.Process, sig: int = signal.SIGKILL) -> None:
        """End ``proc`` on purpose (a test of a lost member, say): its exit is not a failure."""
        self._ended.add(proc.pid)
        (self._children.get(proc.pid) or Child("", proc, None, group=False)).signal(sig)

    async def stop(self) -> None:
        """Kill every process started (and wait for them, at most ``STOP_WAIT`` s)."""
        self._ended.update(p.pid for p in self.procs)
        children = list(self._children.values())
        for c in children:
            c.signal(signal.SIGCONT)  # a test may have stopped it (SIGSTOP)
        await stop(children, [(signal.SIGKILL, STOP_WAIT)])  # a test's processes need no grace
        for task in self._watchers:
            task.cancel()
        await asyncio.gather(*self._watchers, return_exceptions=True)


async def first_line(
    proc: asyncio.subprocess.Process, wanted: Callable[[str], bool], timeout: float
) -> str | None:
    """The first line of ``proc``'s output (piped) for which ``wanted`` is true, the lines before
    it skipped; None if the output ends first. Raises TimeoutError after ``timeout`` seconds."""
    assert proc.stdout is not None
    async with asyncio.timeout(timeout):
        while line := (await proc.stdout.readline()).decode():
            if wanted(line):
                return line
    return None


def _file_name(label: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in label)[:60]


@asynccontextmanager
async def cluster(team: TeamCredentials | None = None, **kwargs: object) -> AsyncIterator[Cluster]:
    """A cluster whose processes are all killed on exit."""
    c = Cluster(team or TeamCredentials.generate("alpha"), **kwargs)  # type: ignore[arg-type]
    try:
        yield c
    finally:
        await c.stop()


async def serve_programs(
    name: str, programs: Mapping[str, Callable[..., Any]], *, timeout: float = 30.0
) -> None:
    """Be the team member ``name`` hosting ``programs`` (no hardware) until stdin closes.

    The body of a helper process started with :meth:`Cluster.start`: team and zenoh settings
    come from the environment, and it prints ``READY`` once it is a member (TimeoutError after
    ``timeout`` s)::

        if __name__ == "__main__":
            asyncio.run(serve_programs(sys.argv[1], {"my_program": my_program}))
    """
    async with Node(
        name, TeamCredentials.from_env(), config=NodeConfig.from_env(), unique=True
    ) as node:
        ProgramHost(node, programs, robot=None)
        await node.membership.wait_for({name}, timeout=timeout)
        print("READY", flush=True)
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)
