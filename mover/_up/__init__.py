"""`mover up TEAM.toml`: one file starts a team and keeps it running.

The file (:mod:`._teamfile`) names the team and its key, the seeds, a world process, groups of
robot and workstation processes, and a program to start once everyone is a member. ``mover up``
starts a zenoh router first when the team is large (:func:`needs_router`), then the world and
the members, each as ``python -m mover._cli VERB`` (this package imports none of the packages
whose processes it starts); it waits until all are members of the team, starts the program,
and keeps the team up until Ctrl-C or SIGTERM (exit 0) or until a process marked
``required`` exits (exit 1). Everything goes to a run folder (default
``runs/<team>-<UTC time>/``): ``team.json`` (the file as run, with its seeds), one ``<name>.log``
per process, ``team.key`` when the key is fresh, the world's recording.
"""

from __future__ import annotations

import argparse
import asyncio
import datetime
import sys
from pathlib import Path
from typing import Any

from .._exceptions import ConfigError
from .._procs import ProcessExited
from ..cli import add_command
from . import _hosts
from ._plan import PEER_MESH_MAX, members, needs_router
from ._program import run_program
from ._supervisor import Stopped, Supervisor, UpError
from ._teamfile import TeamFileError, TeamPlan, load_team

__all__ = [
    "PEER_MESH_MAX",
    "ProcessExited",
    "Stopped",
    "Supervisor",
    "TeamFileError",
    "TeamPlan",
    "UpError",
    "load_team",
    "needs_router",
    "register",
    "run_dir",
]


DESCRIPTION = (
    "Start the team a team file describes (a zenoh router when the team is large, the world, "
    "robot and workstation groups), wait until every process is a member, start its program, "
    "and keep the team up until Ctrl-C or SIGTERM (exit 0) or until a required process exits "
    "(exit 1). One log per process, the file as run (team.json, with its seeds) and, for a "
    "fresh key, team.key go to the run folder."
)


def register(sub: Any) -> None:
    """Add ``mover up``."""
    p = add_command(
        sub, "up", run, "start a team from a team file and keep it running", DESCRIPTION
    )
    add_arguments(p)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """``mover up``'s options."""
    p.add_argument("teamfile", metavar="TEAM.toml", help="the team file")
    p.add_argument("--out", metavar="DIR", help="the run folder (default runs/<team>-<UTC time>)")
    p.add_argument("--seed", type=int, help="the run seed (default: the file's, else fresh)")
    p.add_argument(
        "--exit-after-run",
        action="store_true",
        help="stop the team once the program's run has ended (exit 1 if a member failed)",
    )
    p.add_argument("--check", action="store_true", help="check the file, print the plan, exit")
    p.add_argument(
        "--host",
        metavar="NAME",
        help="start this host's part of a team across hosts (the file's [[hosts]])",
    )
    p.add_argument(
        "--gen-config",
        metavar="DIR",
        help="write certificates, the router's ACL and every process's config for a team "
        "across hosts to DIR, then exit (copy DIR to every host; [team] tls names it)",
    )


def run_dir(plan: TeamPlan, out: str | None) -> Path:
    """The run folder: ``out``, else ``runs/<team>-<UTC time>``."""
    if out:
        return Path(out)
    stamp = datetime.datetime.now(datetime.UTC).strftime("%Y%m%dT%H%M%SZ")
    return Path("runs") / f"{plan.name}-{stamp}"


def run(args: argparse.Namespace) -> int:
    """Run ``mover up`` as the command line asks."""
    from ..cli import UsageError

    try:
        plan = load_team(args.teamfile)
    except TeamFileError as exc:
        raise UsageError(str(exc)) from None
    if args.seed is not None and not 0 <= args.seed < 2**63:
        raise UsageError(f"--seed must be from 0 to 2**63-1, got {args.seed}")
    if args.exit_after_run and plan.program is None:
        raise UsageError(f"--exit-after-run: {args.teamfile} has no [program]")
    if args.check:
        return _check(plan)
    if args.gen_config:
        return _gen_config(plan, Path(args.gen_config))
    try:
        verbose = getattr(args, "verbose", 0)
        level = getattr(args, "log_level", None) or {0: None, 1: "INFO"}.get(verbose, "DEBUG")
        out = run_dir(plan, args.out)
        return asyncio.run(up(plan, out, args.seed, args.exit_after_run, level, args.host))
    except UpError as exc:
        print(f"mover up: {exc}", file=sys.stderr)
        return 1


def _check(plan: TeamPlan) -> int:
    n = members(plan)
    topology = plan.topology if plan.topology != "auto" else "auto: "
    if plan.topology == "auto":
        topology += "router" if needs_router(n) else "peer mesh"
    world = f"{plan.world.kind} world {plan.world.file}" if plan.world else "no world"
    started = len(plan.members) + (plan.world is not None)
    print(
        f"{plan.source}: team {plan.name!r}, {started} processes and mover up itself: "
        f"{n} members ({topology}), {world}"
    )
    for h in plan.hosts:
        role = f"router at {_hosts.endpoint(plan)}, " if h.router else ""
        on = [m.name for m in plan.members if m.host == h.name]
        on = ([plan.world.name] if plan.world and plan.world.host == h.name else []) + on
        print(f"  host {h.name} ({h.address}): {role}{', '.join(on) or 'nothing'}")
    for m in plan.members:
        print(
            f"  {m.name}: {m.kind}, hardware {m.hardware}" + (" (required)" if m.required else "")
        )
    if plan.program is not None:
        print(f"  program {plan.program.name} as run {plan.program.run!r}")
    return 0


def _gen_config(plan: TeamPlan, directory: Path) -> int:
    from ..cli import UsageError

    try:
        written = _hosts.generate(plan, directory)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:
        raise UsageError(f"--gen-config {directory}: {exc.strerror or exc}") from None
    for path in written:
        print(path)
    tls = f'tls = "{directory}"' if plan.tls is None else f"tls = {str(plan.tls)!r}"
    hosts = " ".join(h.name for h in plan.hosts)
    print(f"next: copy {directory} to every host ({hosts}), set {tls} in [team] of "
          f"{plan.source}, run `mover up {plan.source} --host NAME` on each; tools such as "
          f"mover run use {directory}/member-{_hosts.WORKSTATION}.json")  # fmt: skip
    return 0


def join_line(sup: Supervisor) -> str:
    """The environment another process needs to join the team ``sup`` runs."""
    plan = sup.plan
    line = f"MOVER_TEAM={plan.name} MOVER_CONNECT={sup.endpoint}"
    if sup.host is not None:
        line += " MOVER_MODE=client MOVER_LISTEN="
        if plan.tls is not None:
            tool = plan.tls / f"member-{_hosts.WORKSTATION}.json"
            line = f"MOVER_TEAM={plan.name} MOVER_MODE=client MOVER_ZENOH_CONFIG={tool}"
    return f"{line} and the team key ({sup.key_source})"


async def up(
    plan: TeamPlan,
    out: Path,
    seed: int | None,
    exit_after_run: bool,
    level: str | None = None,
    host: str | None = None,
) -> int:
    """Start the team (across hosts: ``host``'s part), wait for it, run its program, keep it
    up; the exit status."""
    sup = Supervisor(plan, out=out, seed=seed, log_level=level, host=host)
    s = sup.seeds
    where = f"{'router' if sup.router else 'peer mesh'} on 127.0.0.1:{sup.port}"
    if host is not None:
        where = f"host {host}, through the router at {sup.endpoint}"
    sup.say(f"team {plan.name!r} from {plan.source}: run seed {s.run} (world {s.world}, "
            f"program {s.program}); {where}; run folder {out}")  # fmt: skip
    try:
        async with sup:
            took = await sup.wait_ready()
            sup.say(f"ready in {took:.1f} s: {len(sup.children)} processes; join with "
                    f"{join_line(sup)}")  # fmt: skip
            if plan.program is not None and (host is None or sup.router):
                ok = await sup.guard(run_program(sup))
                if exit_after_run:
                    return 0 if ok else 1
            await sup.wait_stopped()
    except Stopped:
        return 0
    except ProcessExited as exc:
        print(f"mover up: {exc}", file=sys.stderr)
        return 1
    return 0
