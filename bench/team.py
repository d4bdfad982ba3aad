"""Idle cost and load tolerance of a team of member processes, in both topologies.

    python bench/team.py [--members 50] [--seconds 60] [--idle-seconds 10]
                         [--call-timeout 5] [--stress K] [--lease-ms MS]
                         [--parts robot,idle,load]

(a) Idle CPU: 10 and ``--members`` member processes (plain nodes exporting one procedure) are
started in the topology ``mover up`` picks for that many (``mover._up.needs_router``: a peer
mesh, or clients of one ``mover router``), and again in the other one. Once every member sees
the whole team (readiness by membership), the CPU time of every process of the team (members
and router, from /proc) is read over a fixed window of ``--idle-seconds``: ``idle_cpu_N`` in
CPU-s per s in the picked topology, ``idle_cpu_N_other`` in the other one and
``idle_ratio_N = idle_cpu_N / idle_cpu_N_other`` (measured in the same run).

With the 10 members, ``ps_wall_s_10`` and ``call_wall_s``: the wall time of ``mover ps`` and of
``mover call m000 echo`` run as a user runs them (a new process each; median of three).

(r) ``robot_rss_mb``: the RSS of a ``mover robot`` process (``python -m robots``) in a lock-step
world, after its first ticks; ``robot_pss_mb`` its proportional set size (the pages it shares
with the other processes of the run, libraries mostly, counted in shares) and
``robot_rss_shared_libs_mb`` the part of its RSS that is the zenoh, cryptography, OpenSSL and
Python libraries' file pages (the same pages in every robot process of a machine).

(b) Load: ``--members`` members in the picked topology, each calling random others in a loop
(one call in flight, a bounded ``--call-timeout``) for ``--seconds``. ``lost_replies_N``: calls
that timed out or failed while the callee was alive (no member is stopped, and every one is
checked alive at the end); ``member_flaps_N``: leave events seen by any member, from readiness
to the end, for a member that never died (joins seen again are not counted twice). Also
``load_calls_per_s_N`` and ``load_p99_ms_N``, beside ``idle_call_p50_ms_N``, the round trip
of the same calls made one at a time before the load (the baseline of the same run).
``--stress K`` adds K busy-loop processes during the load and ``--cpus 0`` pins every process
to one core (CPU starvation with few processes); ``--topology`` forces the load's topology.

Every figure is one the run measured; the last line is one JSON object of them. A member runs
as ``python bench/team.py --member NAME --size N``.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import random
import statistics
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mover import CallError, Node, NodeConfig, TeamCredentials  # noqa: E402
from mover._config import free_port  # noqa: E402
from mover._up import needs_router  # noqa: E402  # the topology rule `mover up` uses

TICK = os.sysconf("SC_CLK_TCK")


# -- a member -----------------------------------------------------------------------------------


async def member(name: str, size: int) -> None:
    """A team member: answers ``echo``; on ``load S T`` calls random others for S seconds;
    on ``report`` says which members it saw leave since it was ready."""
    names = [f"m{i:03d}" for i in range(size)]
    others = [n for n in names if n != name]
    rng = random.Random(name)
    async with Node(
        name, TeamCredentials.from_env(), kind="bench", config=NodeConfig.from_env()
    ) as node:
        node.export(lambda data: data, "echo")
        await node.membership.wait_for(names, timeout=60 + 2 * size)
        left: list[tuple[str, float]] = []  # who, and when (CLOCK_MONOTONIC, machine-wide)

        async def watch() -> None:
            async for event in node.membership.events():
                if event.kind == "leave":
                    left.append((event.name, time.monotonic()))

        watcher = asyncio.create_task(watch())
        print("READY", flush=True)
        loop = asyncio.get_running_loop()
        while line := (await loop.run_in_executor(None, sys.stdin.readline)).split():
            if line[0] == "ping":  # calls one at a time: the unloaded round trip
                times = []
                for other in others[: int(line[1])]:
                    t0 = time.perf_counter()
                    await node.call(other, "echo", b"x" * 64, timeout=float(line[2]))
                    times.append(time.perf_counter() - t0)
                print(json.dumps({"times": times}), flush=True)
            elif line[0] == "load":
                result = await _load(node, others, rng, *map(float, line[1:3]))
                print(json.dumps(result), flush=True)
            elif line[0] == "report":
                print(json.dumps({"left": left}), flush=True)
        watcher.cancel()


async def _load(
    node: Node, others: list[str], rng: random.Random, seconds: float, timeout: float
) -> dict[str, Any]:
    """Call random others, one call in flight, for ``seconds``."""
    failed: list[list[str]] = []
    times: list[float] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        other = rng.choice(others)
        t0 = time.perf_counter()
        try:
            await node.call(other, "echo", b"x" * 64, timeout=timeout)
        except CallError as exc:
            failed.append([other, type(exc).__name__])
            await asyncio.sleep(0.01)  # an unknown member fails at once: do not spin
        else:
            times.append(time.perf_counter() - t0)
    return {"ok": len(times), "failed": failed, "times": times}


# -- the team -----------------------------------------------------------------------------------


class Processes:
    """The processes of one team in one topology: members and, behind a router, the router."""

    def __init__(self, size: int, router: bool, env: dict[str, str]) -> None:
        self.size, self.router, self.env = size, router, env
        self.names = [f"m{i:03d}" for i in range(size)]
        self.members: dict[str, asyncio.subprocess.Process] = {}
        self.hub: asyncio.subprocess.Process | None = None
        self.tool_env: dict[str, str] = {}

    @property
    def label(self) -> str:
        return "router" if self.router else "peer"

    def pids(self) -> list[int]:
        procs = [*self.members.values(), *([self.hub] if self.hub else [])]
        return [p.pid for p in procs]

    async def start(self) -> None:
        team, port = TeamCredentials.generate("bench"), free_port()
        seed = f"tcp/127.0.0.1:{port}"
        base = {**self.env, **team.env()}
        mode = "client" if self.router else "peer"  # how a tool reaches this team
        self.tool_env = {**base, **NodeConfig(mode=mode, listen=(), connect=(seed,)).env()}
        if self.router:
            self.hub = await _spawn(
                [sys.executable, "-m", "mover", "router", "--listen", seed], base
            )
            assert self.hub.stdout is not None
            await asyncio.wait_for(self.hub.stdout.readline(), 30)
        for i, name in enumerate(self.names):
            if self.router:
                config = NodeConfig(mode="client", listen=(), connect=(seed,))
            elif i == 0:  # the first member is the seed the others connect to
                config = NodeConfig(listen=(seed,))
            else:
                config = NodeConfig(connect=(seed,))
            env = {**base, **config.env()}
            args = [sys.executable, __file__, "--member", name, "--size", str(self.size)]
            self.members[name] = await _spawn(args, env, stdin=True)
        await asyncio.wait_for(
            asyncio.gather(*(self._line(p) for p in self.members.values())),
            timeout=90 + 3 * self.size,
        )

    async def _line(self, proc: asyncio.subprocess.Process) -> str:
        assert proc.stdout is not None
        line = (await proc.stdout.readline()).decode()
        if not line:
            raise RuntimeError(f"a member exited (status {await proc.wait()})")
        return line

    async def ask(self, command: str, only: int | None = None) -> list[dict[str, Any]]:
        """Send ``command`` to every member (or the first ``only``); each one's JSON answer."""
        procs = list(self.members.values())[:only]
        for proc in procs:
            assert proc.stdin is not None
            proc.stdin.write(command.encode() + b"\n")
        lines = await asyncio.gather(*(self._line(p) for p in procs))
        return [json.loads(line) for line in lines]

    def alive(self) -> bool:
        return all(p.returncode is None for p in self.members.values())

    async def stop(self) -> None:
        procs = [*self.members.values(), *([self.hub] if self.hub else [])]
        for p in self.members.values():
            if p.stdin is not None and p.returncode is None:
                p.stdin.close()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(asyncio.gather(*(p.wait() for p in self.members.values())), 20)
        for p in procs:
            if p.returncode is None:
                p.kill()
            await p.wait()


async def _spawn(
    args: list[str], env: dict[str, str], *, stdin: bool = False
) -> asyncio.subprocess.Process:
    return await asyncio.create_subprocess_exec(
        *args,
        env=env,
        cwd=ROOT,
        stdin=asyncio.subprocess.PIPE if stdin else asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
    )


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU time so far of the processes ``pids`` (all their threads)."""
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])  # utime, stime (fields 14 and 15)
    return total / TICK


async def idle_cpu(
    size: int, router: bool, window: float, env: dict[str, str], cli: dict[str, float] | None = None
) -> float:
    """CPU-s per s of a ready, idle team of ``size`` members over ``window`` seconds; with
    ``cli``, then the wall time of ``mover ps`` and ``mover call`` on it (median of three)."""
    team = Processes(size, router, env)
    try:
        await team.start()
        await asyncio.sleep(1.0)  # the last hellos and gossip settle
        before, t0 = cpu_seconds(team.pids()), time.monotonic()
        await asyncio.sleep(window)
        used = cpu_seconds(team.pids()) - before
        rate = used / (time.monotonic() - t0)
        flaps = sum(len(r["left"]) for r in await team.ask("report"))
        if cli is not None:
            ps = [await _wall(["ps"], team.tool_env, size + 1) for _ in range(3)]
            call = [
                await _wall(["call", "m000", "echo", '"x"'], team.tool_env, 1) for _ in range(3)
            ]
            cli[f"ps_wall_s_{size}"] = round(statistics.median(ps), 3)
            cli["call_wall_s"] = round(statistics.median(call), 3)
            print(f"mover ps, {size} members: {ps} s; mover call: {call} s", flush=True)
        print(
            f"idle, {size:3d} members, {team.label:>6}: {rate:.3f} CPU-s/s "
            f"({rate / size * 1000:.1f} ms/s a member; {flaps} leave events)",
            flush=True,
        )
        return rate
    finally:
        await team.stop()


async def _wall(verb: list[str], env: dict[str, str], lines: int) -> float:
    """Wall seconds of ``mover VERB`` (a fresh process, as a user types it); it must succeed
    and print at least ``lines`` lines."""
    t0 = time.perf_counter()
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *verb, env=env, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    out, err = await asyncio.wait_for(proc.communicate(), 60)
    wall = time.perf_counter() - t0
    if proc.returncode or len(out.splitlines()) < lines:
        raise RuntimeError(f"mover {' '.join(verb)} failed: {err.decode()[-300:]}")
    return wall


async def robot_rss(env: dict[str, str]) -> tuple[float, float, float]:
    """RSS, PSS and the libraries' file pages (MB) of a ``mover robot`` process (``python -m
    robots``) in a lock-step world, after its first ticks (its pose read through the world)."""
    from mover.testing import cluster

    async with cluster() as c, c.launcher() as node:
        await c.world(str(ROOT / "worlds" / "search_and_rescue.toml"), expect=1)
        [proc] = await c.robots("ernst")
        await node.membership.wait_for(["world", "ernst"], timeout=30)
        await node.call("ernst", "robot.pose", timeout=10)
        await asyncio.sleep(1.0)
        rollup = Path(f"/proc/{proc.pid}/smaps_rollup").read_text().splitlines()
        rss, pss = (int(next(x for x in rollup if x.startswith(k)).split()[1]) for k in KEYS)
        libs, name = 0, ""
        for line in Path(f"/proc/{proc.pid}/smaps").read_text().splitlines():
            words = line.split()
            if "-" in words[0] and len(words) >= 5:  # a mapping's first line: its file last
                name = words[5].rsplit("/", 1)[-1] if len(words) > 5 else ""
            elif words[0] == "Rss:" and name.startswith(LIBS):
                libs += int(words[1])
    return rss / 1024, pss / 1024, libs / 1024


KEYS = ("Rss:", "Pss:")
LIBS = ("zenoh.", "_rust.", "libcrypto", "libssl", "libpython")
"""The shared libraries of a robot process whose file pages robot_rss counts apart."""


async def load(
    size: int, seconds: float, timeout: float, stress: int, router: bool, env: dict[str, str]
) -> dict[str, float]:
    """Lost replies and membership flaps of ``size`` members calling each other."""
    team = Processes(size, router, env)
    busy: list[asyncio.subprocess.Process] = []
    try:
        await team.start()
        await asyncio.sleep(1.0)
        pings = await team.ask(f"ping {min(size - 1, 20)} {timeout}", only=1)
        idle_times = [t for r in pings for t in r["times"]]
        busy = [
            await _spawn([sys.executable, "-c", "while True: pass"], env) for _ in range(stress)
        ]
        results = await asyncio.wait_for(
            team.ask(f"load {seconds} {timeout}"), seconds + timeout + 60
        )
        for p in busy:
            p.kill()
        left = [(name, t) for r in await team.ask("report") for name, t in r["left"]]
        if not team.alive():
            raise RuntimeError("a member died during the load: its calls would not count")
    finally:
        for p in busy:
            if p.returncode is None:
                p.kill()
            await p.wait()
        await team.stop()
    times = [t for r in results for t in r["times"]]
    failed = [f for r in results for f in r["failed"]]
    kinds: dict[str, int] = {}
    for _, kind in failed:
        kinds[kind] = kinds.get(kind, 0) + 1
    when = [t for _, t in left]
    spread = f" within {max(when) - min(when):.2f} s" if when else ""
    p99 = statistics.quantiles(times, n=100)[98] * 1000 if len(times) > 1 else float("nan")
    p50_idle = statistics.median(idle_times) * 1000
    print(
        f"load, {size} members ({team.label}, {stress} busy loops, {seconds:.0f} s): "
        f"{len(times)} calls answered, {len(failed)} lost {kinds or ''}, "
        f"{len(left)} leave events{spread} {sorted({n for n, _ in left}) or ''}; "
        f"p99 {p99:.1f} ms "
        f"(unloaded p50 {p50_idle:.2f} ms)",
        flush=True,
    )
    return {
        f"lost_replies_{size}": len(failed),
        f"member_flaps_{size}": len(left),
        f"load_calls_per_s_{size}": round(len(times) / seconds, 1),
        f"load_p99_ms_{size}": round(p99, 2),
        f"idle_call_p50_ms_{size}": round(p50_idle, 3),
    }


async def main(args: argparse.Namespace) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    if args.lease_ms:
        env["MOVER_LEASE_MS"] = str(args.lease_ms)
    out: dict[str, Any] = {"lease_ms": NodeConfig.from_env().lease}
    if args.lease_ms:
        out["lease_ms"] = args.lease_ms
    parts = set(args.parts.split(","))
    if "robot" in parts:
        rss, pss, libs = await robot_rss(env)
        out["robot_rss_mb"] = round(rss, 1)
        out["robot_pss_mb"] = round(pss, 1)
        out["robot_rss_shared_libs_mb"] = round(libs, 1)
        print(
            f"a robot process in a lock-step world: {rss:.1f} MB RSS ({pss:.1f} MB PSS; "
            f"{libs:.1f} MB of it the zenoh, cryptography, OpenSSL and Python libraries)",
            flush=True,
        )
    if "idle" in parts:
        for size in sorted({10, args.members}):
            picked = needs_router(size)
            cli = out if size == 10 else None
            mine = await idle_cpu(size, picked, args.idle_seconds, env, cli)
            try:
                other: float | None = await idle_cpu(size, not picked, args.idle_seconds, env)
            except (RuntimeError, TimeoutError) as exc:  # a 50-peer mesh may never assemble
                print(f"idle, {size:3d} members, the other topology: not ready: {exc}", flush=True)
                other = None
            out[f"idle_topology_{size}"] = "router" if picked else "peer"
            out[f"idle_cpu_{size}"] = round(mine, 4)
            out[f"idle_cpu_{size}_other"] = round(other, 4) if other is not None else None
            out[f"idle_ratio_{size}"] = round(mine / other, 3) if other else None
    if "load" in parts:
        router = (
            needs_router(args.members) if args.topology == "auto" else args.topology == "router"
        )
        out[f"load_topology_{args.members}"] = "router" if router else "peer"
        out.update(
            await load(args.members, args.seconds, args.call_timeout, args.stress, router, env)
        )
    return out


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--members", type=int, default=50, help="team size (default 50)")
    p.add_argument("--seconds", type=float, default=60.0, help="load duration (default 60)")
    p.add_argument("--idle-seconds", type=float, default=10.0, help="idle window (default 10)")
    p.add_argument("--call-timeout", type=float, default=5.0, help="a call's bound (default 5)")
    p.add_argument("--stress", type=int, default=0, help="busy-loop processes during the load")
    p.add_argument("--lease-ms", type=int, default=0, help="MOVER_LEASE_MS for every member")
    p.add_argument(
        "--parts", default="robot,idle,load", help="robot, idle, load (default: all three)"
    )
    p.add_argument(
        "--topology",
        choices=("auto", "peer", "router"),
        default="auto",
        help="of the load (default: the one mover up picks)",
    )
    p.add_argument(
        "--cpus", help="comma-separated CPUs to run everything on (e.g. 0: starve on one core)"
    )
    p.add_argument("--member", help=argparse.SUPPRESS)
    p.add_argument("--size", type=int, help=argparse.SUPPRESS)
    return p


if __name__ == "__main__":
    arguments = _parser().parse_args()
    if arguments.member:
        import zenoh

        zenoh.try_init_log_from_env()  # RUST_LOG=warn says why a link closed
        asyncio.run(member(arguments.member, arguments.size))
    else:
        if not 2 <= arguments.members <= 200:
            _parser().error("--members must be from 2 to 200")
        if arguments.cpus:  # inherited by every process started
            os.sched_setaffinity(0, {int(c) for c in arguments.cpus.split(",")})
        print(json.dumps(asyncio.run(main(arguments))))
