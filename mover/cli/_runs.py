"""The `mover run`, `mover runs` and `mover cancel` verbs: start a program on team members
and follow it, list the runs, cancel one.

What runs where comes from each member's ``mover.status`` (one call per member, bounded by
``STATUS_TIMEOUT``). ``mover run`` remembers the members it found per team name in
``teams.json`` under the state folder (``$MOVER_STATE_DIR``, else ``$XDG_STATE_HOME/mover``,
else ``~/.local/state/mover``) and warns when the next run finds others.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import os
import secrets
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._config import NodeConfig, TeamCredentials
from .._exceptions import CallError
from .._keys import check_name
from . import (
    UsageError,
    add_command,
    json_object,
    member_name,
    seed,
    team_from_args,
)
from ._verbs import (
    NO_ANSWER,
    _listing,
    _on_team,
    _plain,
    _statuses,
    _team_options,
    discover,
    observe,
)

if TYPE_CHECKING:
    from .._node import Node

    Sub = argparse._SubParsersAction[argparse.ArgumentParser]

log = logging.getLogger("mover.cli")

STATE_ENV = "MOVER_STATE_DIR"
PROBE_EVERY = 2.0
"""Seconds between the probes ``mover run`` makes of the members it waits for (a fresh hello
each: :meth:`mover.Membership.probe`), to say when it waits for unreachable ones."""
_TEAMS_KEPT = 100  # team names teams.json remembers
_STATE_LIMIT = 1 << 20  # bytes of teams.json read at most


# -- run ------------------------------------------------------------------------------------------


def register_run(sub: Sub) -> None:
    """Add ``mover run``."""
    p = add_command(sub, "run", run_run, "start an installed program on members of a team")
    p.add_argument("program", nargs="?")
    p.add_argument(
        "--robots",
        help="comma-separated members (default: every member that is not a tool or a world)",
    )
    p.add_argument(
        "--args", metavar="JSON", default="{}", help="the program's arguments as a JSON object"
    )
    p.add_argument("--detach", action="store_true", help="exit once the run has started")
    p.add_argument("--run-id", type=member_name, help="name of the run (default: PROGRAM-<random>)")
    p.add_argument(
        "--seed", type=seed, help="seed of the run's random choices (default: from the run id)"
    )
    p.add_argument(
        "--share",
        action="store_true",
        help="run beside runs under way that were started with --share too",
    )
    p.add_argument(
        "--survivors",
        action="store_true",
        help="a member lost during a step does not fail the run: the others go on without it",
    )
    p.add_argument(
        "--attach",
        metavar="RUN",
        type=member_name,
        help="follow a run started earlier (progress and outcomes) instead of starting one",
    )
    _team_options(p)


def run_run(args: argparse.Namespace) -> int:
    """Starts PROGRAM on every chosen member (no code is sent: members run their installed copy),
    shows progress, and prints each member's outcome. The launcher is not a coordinator: with
    --detach it exits once the run has started; --attach RUN follows it again."""
    if args.attach is not None:
        if args.program is not None:
            raise UsageError("give a PROGRAM to start or --attach RUN, not both")
        team, config = team_from_args(args)
        return asyncio.run(_attach(team, config, args))
    if args.program is None:
        raise UsageError("a PROGRAM to start is needed (or --attach RUN)")
    kwargs = json_object(args.args, "--args")
    try:
        check_name("program", args.program)
        robots = (
            [check_name("robot", r) for r in args.robots.split(",") if r] if args.robots else None
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    team, config = team_from_args(args)
    return asyncio.run(_run(team, config, args, robots, kwargs))


def _progress(node: Node, run: str) -> asyncio.Task[None]:
    """Print the progress reports of run ``run`` as they come (a task; cancel it to stop)."""
    from .._programs import PROGRESS_TOPIC

    progress = node.subscribe(f"{PROGRESS_TOPIC}/{run}")
    started = time.monotonic()

    async def show() -> None:
        async for m in progress:
            if not isinstance(m.data, dict):
                continue
            info = {k: v for k, v in m.data.items() if k not in ("member", "phase")}
            extra = " ".join(f"{k}={_short(v)}" for k, v in info.items())
            print(
                f"[{time.monotonic() - started:6.1f}s] {m.data.get('member')}: "
                f"{m.data.get('phase')} {extra}".rstrip(),
                flush=True,
            )

    return asyncio.create_task(show())


def _watch(node: Node, members: list[str]) -> asyncio.Task[None]:
    """While the outcomes are awaited: probe the members every ``PROBE_EVERY`` s and say, in
    one line each time it changes, which ones do not answer (they are suspected: the run waits
    for them for the team's patience) and when they answer again (a task; cancel it)."""
    started = time.monotonic()
    patience = node.config.patience

    async def watch() -> None:
        said: set[str] = set()
        while True:
            await asyncio.sleep(PROBE_EVERY)
            silent = await node.membership.probe(members)
            now = f"[{time.monotonic() - started:6.1f}s]"
            if back := said - silent.keys():
                print(f"{now} {', '.join(sorted(back))}: answering again", flush=True)
            if silent.keys() - said:
                print(
                    f"{now} waiting for {', '.join(sorted(silent))}: no answer for "
                    f"{max(silent.values()):.0f} s (unreachable, not known dead: the run waits "
                    f"up to the patience, {patience:g} s)",
                    flush=True,
                )
            said = set(silent)

    return asyncio.create_task(watch())


async def _run(
    team: TeamCredentials,
    config: NodeConfig,
    args: argparse.Namespace,
    robots: list[str] | None,
    kwargs: dict[str, Any],
) -> int:
    from .._node import Node
    from .._programs import launch, outcomes

    run = args.run_id or f"{args.program}-{secrets.token_hex(3)}"
    async with Node(
        f"run-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        try:
            if robots:
                await node.membership.wait_for(robots, timeout=args.wait)
            else:
                await discover(node, args.wait)
        except TimeoutError:
            missing = sorted(set(robots or ()) - node.membership.members())
            print(f"mover run: not in team {team.name!r}: {', '.join(missing)}", file=sys.stderr)
            return 1
        members = robots or sorted(
            n
            for n in node.membership.members()
            if (i := node.membership.info(n)) is not None and i.kind not in ("tool", "world")
        )
        if not members:
            print(f"mover run: no members in team {team.name!r}", file=sys.stderr)
            return 1
        if robots is None:
            _check_team(team.name, members)
        shower = _progress(node, run)
        try:
            await launch(
                node,
                args.program,
                members,
                kwargs,
                run=run,
                wait=False,
                seed=args.seed,
                share=args.share,
                policy="survivors" if args.survivors else "fail",
            )
            # said once every member has started it: from now on they know the run
            print(f"run {run}: {args.program} on {', '.join(members)}", flush=True)
            if not args.detach:
                watch = _watch(node, members)
                try:
                    ends = await outcomes(node, run, members)
                except asyncio.CancelledError:  # Ctrl-C, SIGTERM: the run is the members'
                    print(
                        f"mover run: stopped watching; run {run} goes on on the members: "
                        f"`mover run --attach {run}` follows it, `mover cancel {run}` ends it",
                        file=sys.stderr,
                        flush=True,
                    )
                    raise
                finally:
                    watch.cancel()
        except CallError as exc:
            print(f"mover run: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 1
        finally:
            await asyncio.sleep(0.1)
            shower.cancel()
    if args.detach:
        print(f"run {run} started; the members go on without this launcher")
        print(f"follow it with: mover run --attach {run}; end it with: mover cancel {run}")
        return 0
    return _print_outcomes(ends)


def _print_outcomes(outcomes: dict[str, dict[str, Any]]) -> int:
    failed = 0
    for member, outcome in outcomes.items():
        if "error" in outcome:
            failed += 1
            print(f"{member}: FAILED {outcome['error']}")
            if outcome.get("traceback"):  # a bug in the program: where it happened
                print("  " + str(outcome["traceback"]).rstrip().replace("\n", "\n  "))
        else:
            print(f"{member}: {json.dumps(outcome.get('result'), default=_plain)}")
    return 1 if failed else 0


async def _find_run(
    node: Node, run: str, wait: float
) -> tuple[dict[str, dict[str, Any]], dict[str, list[dict[str, Any]] | str]]:
    """Who knows run ``run``: {member: its status of the run}, and every member's statuses."""
    await discover(node, wait)
    names = sorted(
        n for n in node.membership.members() if (i := node.membership.info(n)) and i.kind != "tool"
    )
    statuses = await _statuses(node, names)
    found = {
        member: entry
        for member, runs in statuses.items()
        if isinstance(runs, list)
        for entry in runs
        if entry.get("run") == run
    }
    return found, statuses


async def _attach(team: TeamCredentials, config: NodeConfig, args: argparse.Namespace) -> int:
    from .._node import Node
    from .._programs import outcomes

    run = args.attach
    async with Node(
        f"attach-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        shower = _progress(node, run)  # first, so that no report is missed
        try:
            found, _ = await _find_run(node, run, args.wait)
            if not found:
                print(
                    f"mover run: no member of team {team.name!r} knows run {run!r}",
                    file=sys.stderr,
                )
                return 1
            first = next(iter(found.values()))
            members = [m for m in first.get("members", []) if isinstance(m, str)] or list(found)
            print(f"run {run}: {first.get('program')} on {', '.join(members)}", flush=True)
            for member in members:
                entry = found.get(member)
                where = f"{entry.get('state')}, {entry.get('phase')}" if entry else NO_ANSWER
                print(f"  {member}: {where}", flush=True)
            watch = _watch(node, members)
            try:
                ends = await outcomes(node, run, members)
            finally:
                watch.cancel()
        finally:
            await asyncio.sleep(0.1)
            shower.cancel()
    return _print_outcomes(ends)


# -- runs, cancel ---------------------------------------------------------------------------------


def register_runs(sub: Sub) -> None:
    """Add ``mover runs``."""
    _listing(
        sub, "runs", "list the runs on the members of a team", "one JSON object per run", _runs
    )


async def _runs(team: TeamCredentials, config: NodeConfig, args: argparse.Namespace) -> int:
    _, statuses = await observe(team, config, args.wait, "runs")
    runs: dict[str, dict[str, Any]] = {}
    for member, entries in statuses.items():
        for entry in entries if isinstance(entries, list) else ():
            row = runs.setdefault(
                entry["run"],
                {
                    "run": entry["run"],
                    "program": entry.get("program"),
                    "members": entry.get("members"),
                    "started": entry.get("started") or 0.0,
                    "states": {},
                },
            )
            row["states"][member] = f"{entry.get('state')}:{entry.get('phase')}"
    rows = sorted(runs.values(), key=lambda r: (float(r["started"]), r["run"]))
    silent = sorted(m for m, s in statuses.items() if s == NO_ANSWER)
    if args.json:
        for row in rows:
            print(json.dumps(row, default=str))
        return 0
    if silent:
        print(f"mover runs: no answer from {', '.join(silent)}", file=sys.stderr)
    if not rows:
        print(f"no runs on the members of team {team.name!r}")
        return 0
    print(f"{'RUN':<28} {'PROGRAM':<20} {'STARTED':<9} MEMBERS (state:phase)")
    for row in rows:
        when = time.strftime("%H:%M:%S", time.localtime(float(row["started"])))
        states = " ".join(f"{m}={st}" for m, st in sorted(row["states"].items()))
        print(f"{row['run']:<28} {row['program']!s:<20} {when:<9} {states}")
    return 0


def register_cancel(sub: Sub) -> None:
    """Add ``mover cancel``."""
    p = add_command(
        sub, "cancel", _on_team(_cancel), "end a run on every member (their finally blocks run)"
    )
    p.add_argument("run", type=member_name)
    _team_options(p)


async def _cancel(team: TeamCredentials, config: NodeConfig, args: argparse.Namespace) -> int:
    """Cancels RUN on every member that knows it and prints each one's outcome."""
    from .._node import Node
    from .._programs import CANCEL_WAIT

    async with Node(
        f"cancel-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        found, _ = await _find_run(node, args.run, args.wait)
        if not found:
            print(
                f"mover cancel: no member of team {team.name!r} knows run {args.run!r}",
                file=sys.stderr,
            )
            return 1

        async def one(member: str) -> dict[str, Any]:
            try:
                outcome: dict[str, Any] = await node.call(
                    member, "mover.cancel", args.run, f"mover cancel ({node.name})",
                    timeout=CANCEL_WAIT + 5,
                )  # fmt: skip
                return outcome
            except CallError as exc:
                return {"error": f"{type(exc).__name__}: {exc}"}

        members = sorted(found)
        ends = await asyncio.gather(*(one(m) for m in members))
    _print_outcomes(dict(zip(members, ends, strict=True)))
    return 0


# -- the last known team --------------------------------------------------------------------------


def state_dir() -> Path:
    """Where mover keeps its small state: $MOVER_STATE_DIR, else $XDG_STATE_HOME/mover, else
    ~/.local/state/mover."""
    if os.environ.get(STATE_ENV):
        return Path(os.environ[STATE_ENV])
    base = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(base) / "mover"


def _check_team(team: str, members: list[str]) -> None:
    """Warn (one line on stderr) if ``members`` differ from the last ones found for ``team``;
    remember them. A state file that cannot be read or written is not an error."""
    path = state_dir() / "teams.json"
    known: dict[str, Any] = {}
    try:
        with path.open("rb") as f:
            loaded = json.loads(f.read(_STATE_LIMIT))
        if isinstance(loaded, dict):
            known = loaded
    except (OSError, ValueError, RecursionError):
        pass  # no file yet, or not ours to trust: start afresh
    last = known.get(team)
    if isinstance(last, list) and sorted(map(str, last)) != sorted(members):
        gone = sorted(set(map(str, last)) - set(members))
        new = sorted(set(members) - set(map(str, last)))
        said = "; ".join(
            part
            for part in (
                f"missing {', '.join(gone)}" if gone else "",
                f"new {', '.join(new)}" if new else "",
            )
            if part
        )
        print(
            f"mover run: warning: team {team!r} differs from its last run ({said}); "
            f"starting on {', '.join(members)}",
            file=sys.stderr,
        )
    known.pop(team, None)
    known[team] = sorted(members)
    while len(known) > _TEAMS_KEPT:
        del known[next(iter(known))]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(known))
        tmp.replace(path)
    except OSError as exc:
        log.warning("cannot remember the team in %s: %s", path, exc)


def _short(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.2f}"
    if isinstance(value, list) and all(isinstance(v, float) for v in value):
        return "[" + ", ".join(f"{v:.2f}" for v in value) + "]"
    return str(value)
