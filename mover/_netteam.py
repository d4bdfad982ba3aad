"""A team file's team across the hosts of a :class:`~mover._netlab.Netlab`, every process a
client of one router over mutual TLS: the scenario runner of the tests and benchmarks across
hosts.

::

    async with Netlab(("a", "b", "c")) as lab, TeamAcrossHosts(lab, plan, out=run_dir) as team:
        result = await team.run_program(timeout=120)      # `mover run` on host c
        result = await team.run_with_fault("partition")     # b cut off 5 s, 3 s into the run

Host ``router`` (default a) runs ``mover router`` with the config of ``mover router
--gen-config`` (certificates for the world, every member and ``workstation``, the ACL) and the
world; host ``members`` (default b) runs every robot and workstation group of the file, joining
through an :class:`~mover._impair.ImpairProxy` in the router's host (``team.proxy``; it
impairs nothing until told to; its draws seeded by the run seed) when ``proxied``
(default); host ``workstation`` (default c) runs
``mover run`` with the file's program, run name and program seed, as ``mover up`` would start
it. The world and the members are started with the command lines of ``mover up``
(:mod:`mover._up._plan`), so a seed gives the run ``mover up``/``mover demo`` give it on one
machine. Readiness is membership: ``mover run --robots`` waits until the members are in the team.
Every process's output goes to ``<out>/<name>.log``; on exit all are stopped (SIGINT, then
SIGTERM, then SIGKILL, as ``mover up`` does) and the lab kills anything left. With
``router_first=False`` the world and the members start before the router (a router outage at
start: they say so and wait), which :meth:`TeamAcrossHosts.start_router` then starts.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import re
import signal
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from ._config import TeamCredentials
from ._impair import ImpairProxy
from ._netlab import Netlab
from ._procs import Child, Processes, stop
from ._up._plan import Seeds, member_argv, seeds, world_argv
from ._up._teamfile import TeamPlan

__all__ = [
    "LOSSES",
    "WORKSTATION",
    "RunResult",
    "TeamAcrossHosts",
    "last_tick",
    "losses",
    "lost_members",
]

WORKSTATION = "workstation"
"""The certificate name ``mover run`` uses."""
ROUTER_PORT = 7448
PROXY_PORT = 7449
READY_TIMEOUT = 30.0
"""Seconds the router has to say it listens."""
_LADDER = [(signal.SIGINT, 5.0), (signal.SIGTERM, 2.0), (signal.SIGKILL, 2.0)]


@dataclass
class RunResult:
    """How ``mover run`` ended: its exit code (None: killed at the timeout), its lines with the
    seconds since it started, when the run started (its ``run NAME:`` line; None: never) and
    ended, in seconds since ``mover run`` started."""

    code: int | None
    lines: list[tuple[float, str]] = field(default_factory=list)
    started: float | None = None
    ended: float = 0.0
    fault: str | None = None  # what run_with_fault did (None: nothing, the run ended first)

    @property
    def run_s(self) -> float | None:
        """Seconds from the run's start to ``mover run``'s exit."""
        return None if self.started is None else self.ended - self.started

    @property
    def text(self) -> str:
        return "\n".join(line for _, line in self.lines)


class TeamAcrossHosts(Processes):
    """The team of ``plan`` on the hosts of ``lab`` (see the module docstring)."""

    def __init__(
        self,
        lab: Netlab,
        plan: TeamPlan,
        *,
        out: Path,
        seed: int | None = None,
        router: str = "a",
        members: str = "b",
        workstation: str = "c",
        proxied: bool = True,
        router_first: bool = True,
        log_level: str = "WARNING",
        env: dict[str, str] | None = None,
    ) -> None:
        if plan.world is None or plan.program is None:
            raise ValueError(f"{plan.source}: a team across hosts needs a [world] and a [program]")
        self.lab, self.out, self.log_level = lab, out, log_level
        robots = plan.robots()
        self.plan = replace(
            plan, world=replace(plan.world, expect=plan.world.expect or len(robots))
        )
        self.seeds: Seeds = seeds(plan, seed)
        self.where = {"router": router, "members": members, "workstation": workstation}
        self.proxied = proxied
        self.router_first = router_first
        self.team = TeamCredentials.generate(plan.name)
        self.extra_env = env or {}
        self.router: Child | None = None
        self.world: Child | None = None
        self.members: list[Child] = []
        self.proxy: ImpairProxy | None = None
        self._pumps: list[asyncio.Task[int]] = []
        self.run_started = asyncio.Event()
        """Set once the run of :meth:`run_program` has started (its ``run NAME:`` line)."""

    @property
    def recording(self) -> Path:
        """The world's recording (written when the file asks for one)."""
        assert self.plan.world is not None
        return self.out / f"{self.plan.world.name}.jsonl"

    # -- up ------------------------------------------------------------------------------------

    async def _start(self) -> None:
        from .cli._router import generate_config

        assert self.plan.world is not None
        self.out.mkdir(parents=True, exist_ok=True)
        tls = self.out / "tls"
        names = [self.plan.world.name, *(m.name for m in self.plan.members)]
        a = self.lab[self.where["router"]]
        await asyncio.to_thread(
            generate_config, tls, self.plan.name, names, a.address, ROUTER_PORT, [WORKSTATION]
        )
        if self.proxied:  # the members' host joins through the proxy, in the router's host
            self.proxy = ImpairProxy((a.address, ROUTER_PORT), seed=self.seeds.run)
            await self.proxy.start((a.address, PROXY_PORT), netns=a.ns)
            for m in self.plan.members:
                path = tls / f"member-{m.name}.json"
                config = json.loads(path.read_text())
                config["connect/endpoints"] = [f"tls/{a.address}:{PROXY_PORT}"]
                path.write_text(json.dumps(config, indent=2))
        if self.router_first:
            await self.start_router()
        world = world_argv(self.plan.world, self.seeds, self.out)
        self.world = await self._spawn(self.where["router"], self.plan.world.name, world[3:])
        for m in self.plan.members:
            argv = member_argv(m)[3:]
            self.members.append(await self._spawn(self.where["members"], m.name, argv))

    async def start_router(self) -> None:
        """Start ``mover router`` on the router's host; return once it listens."""
        tls = self.out / "tls"
        self.router = await self._spawn(
            self.where["router"],
            "router",
            ["router", "--config", str(tls / "router.json")],
            ready="router ",
        )

    def env(self, cert: str) -> dict[str, str]:
        """The environment of the process with certificate ``cert`` (the router: its own
        config file, no member's)."""
        env = {k: v for k, v in os.environ.items() if not k.startswith("MOVER_")}
        env |= {"MOVER_LOG_LEVEL": self.log_level, "PYTHONUNBUFFERED": "1"}
        if self.plan.patience is not None:  # the router's links last as long as the members'
            env["MOVER_PATIENCE"] = f"{self.plan.patience:g}"
        if cert != "router":
            env |= {
                **self.team.env(),
                "MOVER_MODE": "client",
                "MOVER_LISTEN": "",
                "MOVER_CONNECT": "",
                "MOVER_ZENOH_CONFIG": str(self.out / "tls" / f"member-{cert}.json"),
            }
        return env | self.extra_env

    async def _spawn(
        self, host: str, name: str, args: list[str] | tuple[str, ...], ready: str | None = None
    ) -> Child:
        log = (self.out / f"{name}.log").open("ab")
        child = await self.lab.start(
            host,
            [sys.executable, "-m", "mover._cli", *args],
            env=self.env(name),
            log=log,
            pump=True,
            label=name,
        )
        said = asyncio.Event()

        def heard(line: str) -> None:
            if ready is not None and line.startswith(ready):
                said.set()

        pump = asyncio.ensure_future(child.pump(heard))
        self._pumps.append(pump)
        if ready is not None:
            waiter = asyncio.ensure_future(said.wait())
            await asyncio.wait({waiter, pump}, timeout=READY_TIMEOUT, return_when="FIRST_COMPLETED")
            waiter.cancel()
            if not said.is_set():
                raise RuntimeError(
                    f"{name} on host {host} did not get ready: {list(child.last)[-1:]}"
                )
        return child

    # -- the run -------------------------------------------------------------------------------

    async def run_program(self, timeout: float = 120.0, wait: float = 60.0) -> RunResult:
        """``mover run`` of the file's program on the workstation host, to its end (killed after
        ``timeout`` s): its exit code and lines. ``run_started`` is set when the run starts (a
        fault can be timed from it)."""
        p = self.plan.program
        assert p is not None
        members = list(p.members) or self.plan.robots()
        args = ["run", p.name, "--robots", ",".join(members), "--run-id", p.run or p.name]
        args += ["--seed", str(self.seeds.program), "--wait", f"{wait:g}"]
        args += ["--args", json.dumps(p.args)]
        args += ["--share"] if p.share else []
        args += ["--survivors"] if p.survivors else []
        env = {**self.env(WORKSTATION)}
        child = await self.lab.start(
            self.where["workstation"],
            [sys.executable, "-m", "mover._cli", *args],
            env=env,
            log=(self.out / "run.log").open("ab"),
            pump=True,
            label="run",
        )
        t0 = time.monotonic()
        result = RunResult(code=None)
        self.run_started.clear()

        def heard(line: str) -> None:
            now = time.monotonic() - t0
            result.lines.append((now, line))
            if result.started is None and line.startswith("run "):
                result.started = now
                self.run_started.set()

        pump = asyncio.ensure_future(child.pump(heard))
        try:
            result.code = await asyncio.wait_for(asyncio.shield(pump), timeout)
        except TimeoutError:
            await stop([child], _LADDER)
            with contextlib.suppress(Exception):
                await asyncio.wait_for(pump, 5)
        result.ended = time.monotonic() - t0
        return result

    async def run_with_fault(
        self,
        fault: str | None = None,
        *,
        at: float = 3.0,
        seconds: float = 5.0,
        timeout: float = 120.0,
    ) -> RunResult:
        """:meth:`run_program`, with ``fault`` for ``seconds``, ``at`` seconds into the run (from
        its ``run NAME:`` line): ``"partition"`` pulls the members' host's cable, ``"stall"``
        SIGSTOPs the router. ``result.fault`` says what was done (None if the run ended first).
        """
        if fault not in (None, "partition", "stall"):
            raise ValueError(f"no fault {fault!r}: partition or stall")
        run = asyncio.ensure_future(self.run_program(timeout=timeout))
        done = None
        try:
            if fault is not None:
                started = asyncio.ensure_future(self.run_started.wait())
                await asyncio.wait({run, started}, timeout=60, return_when="FIRST_COMPLETED")
                started.cancel()
                if self.run_started.is_set() and not run.done():
                    await asyncio.sleep(at)
                    if not run.done():
                        await self._fault(fault, seconds)
                        done = f"{fault} {seconds:g} s at +{at:g} s"
            result = await run
        finally:
            if not run.done():
                run.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await run
        result.fault = done
        return result

    async def _fault(self, fault: str, seconds: float) -> None:
        if fault == "partition":
            async with self.lab.partition(self.where["members"], seconds):
                return
        self.stall_router(True)
        try:
            await asyncio.sleep(seconds)
        finally:
            self.stall_router(False)

    def stall_router(self, stopped: bool) -> None:
        """SIGSTOP the router (``stopped``) or SIGCONT it."""
        assert self.router is not None
        self.router.signal(signal.SIGSTOP if stopped else signal.SIGCONT)

    def tracebacks(self) -> dict[str, int]:
        """Tracebacks in each process's log so far (an expected fault prints none)."""
        found = {}
        for log in sorted(self.out.glob("*.log")):
            n = log.read_text(errors="replace").count("Traceback (most recent call last)")
            if n:
                found[log.stem] = n
        return found

    def log_lines(self, pattern: re.Pattern[str]) -> dict[str, list[str]]:
        """The lines of each process's log that ``pattern`` finds."""
        found: dict[str, list[str]] = {}
        for log in sorted(self.out.glob("*.log")):
            lines = [x for x in log.read_text(errors="replace").splitlines() if pattern.search(x)]
            if lines:
                found[log.stem] = lines
        return found

    # -- down ----------------------------------------------------------------------------------

    async def aclose(self) -> None:
        """Stop the members, then the world, then the router (each: SIGINT, SIGTERM, SIGKILL),
        and the proxy."""
        if self.router is not None:
            self.router.signal(signal.SIGCONT)
        await stop(self.members, _LADDER)
        if self.world is not None:
            await stop([self.world], _LADDER)
        if self.router is not None:
            await stop([self.router], _LADDER)
        if self.proxy is not None:
            await self.proxy.close()
        if self._pumps:
            await asyncio.wait(self._pumps, timeout=5)


LOSSES = re.compile(r"MemberLost|RobotLost|WorldLost|RobotDropped|left the team|lost \[")
"""What a line that tells of a lost member (or a lost world) says."""


def losses(result: RunResult, team: TeamAcrossHosts) -> dict[str, int]:
    """Lines telling of a lost member or world, per process (``run``: ``mover run``'s)."""
    found = {k: len(v) for k, v in team.log_lines(LOSSES).items()}
    in_run = sum(bool(LOSSES.search(line)) for _, line in result.lines)
    if in_run:
        found["run"] = in_run
    return found


_NAMED = re.compile(r"lost \[([^\]]*)\]|'?([\w-]+)'? left the team")


def lost_members(result: RunResult, team: TeamAcrossHosts) -> set[str]:
    """The members some process or ``mover run`` said were lost (or left the team)."""
    lines = [line for v in team.log_lines(LOSSES).values() for line in v]
    lines += [line for _, line in result.lines]
    names: set[str] = set()
    for line in lines:
        for listed, one in _NAMED.findall(line):
            names.update(n.strip(" '\"") for n in listed.split(",") if n.strip())
            if one:
                names.add(one)
    return names


def last_tick(recording: Path) -> float | None:
    """The simulated time of the last tick of a recording (None: no tick yet)."""
    try:
        with recording.open("rb") as f:
            f.seek(max(0, f.seek(0, os.SEEK_END) - 65536))
            tail = f.read().decode(errors="replace").splitlines()
    except OSError:
        return None
    for line in reversed(tail):
        with contextlib.suppress(ValueError):
            data = json.loads(line)
            if isinstance(data, dict) and data.get("type") == "tick":
                return float(data["t"])
    return None
