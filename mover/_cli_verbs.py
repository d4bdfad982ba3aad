"""The `mover ps`, `mover call` and `mover keygen` verbs.

Team and transport come from ``--team`` and the MOVER_* environment (see ``mover._config``);
``--connect`` adds endpoints to reach the team. Both are :func:`mover.cli.add_team_arguments`'.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import secrets
import sys
from typing import TYPE_CHECKING, Any

from ._config import NodeConfig, Team
from ._exceptions import CallError, WireError
from ._keys import check_name
from .cli import (
    UsageError,
    add_team_arguments,
    json_argument,
    json_object,
    member_name,
    positive,
    team_from_args,
)

if TYPE_CHECKING:
    Sub = argparse._SubParsersAction[argparse.ArgumentParser]


def _team_options(p: argparse.ArgumentParser) -> None:
    add_team_arguments(p)
    p.add_argument(
        "--wait",
        type=float,
        default=2.0,
        metavar="S",
        help="seconds to wait for the team to be discovered (default 2)",
    )


# -- ps -------------------------------------------------------------------------------------------


def register_ps(sub: Sub) -> None:
    """Add ``mover ps``."""
    p = sub.add_parser("ps", help="list the live members of a team")
    _team_options(p)
    p.add_argument("--json", action="store_true", help="one JSON object per member")
    p.set_defaults(func=run_ps)


def run_ps(args: argparse.Namespace) -> int:
    team, config = team_from_args(args)
    return asyncio.run(_ps(team, config, args))


async def _ps(team: Team, config: NodeConfig, args: argparse.Namespace) -> int:
    from ._node import Node

    async with Node(
        f"ps-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        await asyncio.sleep(args.wait)
        infos = [node.team.info(n) for n in sorted(node.team.members())]
    rows = [i for i in infos if i is not None]
    if args.json:
        for i in rows:
            print(
                json.dumps(
                    {
                        "name": i.name,
                        "kind": i.kind,
                        "uptime_s": round(i.uptime, 1),
                        "pid": i.pid,
                        "host": i.host,
                    }
                )
            )
        return 0
    if not rows:
        print(f"no members of team {team.name!r} seen within {args.wait} s", file=sys.stderr)
        return 1
    print(f"{'NAME':<16} {'KIND':<12} {'UPTIME':>10} {'PID':>8}  HOST")
    for i in rows:
        print(f"{i.name:<16} {i.kind:<12} {_duration(i.uptime):>10} {i.pid:>8}  {i.host}")
    return 0


def _duration(seconds: float) -> str:
    s = int(seconds)
    return f"{s // 3600}h{s % 3600 // 60:02d}m" if s >= 3600 else f"{s // 60}m{s % 60:02d}s"


# -- call -----------------------------------------------------------------------------------------


def register_call(sub: Sub) -> None:
    """Add ``mover call``."""
    p = sub.add_parser(
        "call",
        help="call a robot's exported procedure",
        description="Arguments are JSON values: 3, 1.5, '\"text\"', '[1, 2]'.",
    )
    p.add_argument("robot")
    p.add_argument("procedure")
    p.add_argument("args", nargs="*", metavar="JSON", help="positional arguments, each JSON")
    p.add_argument("--kwargs", metavar="JSON", help="keyword arguments as a JSON object")
    p.add_argument("--timeout", type=positive, default=10.0, help="seconds (default 10)")
    _team_options(p)
    p.set_defaults(func=run_call)


def run_call(args: argparse.Namespace) -> int:
    try:
        check_name("robot", args.robot)
        check_name("procedure", args.procedure)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    positional = [json_argument(a, f"argument {i + 1}") for i, a in enumerate(args.args)]
    kwargs = json_object(args.kwargs, "--kwargs") if args.kwargs else {}
    team, config = team_from_args(args)
    return asyncio.run(_call(team, config, args, positional, kwargs))


async def _call(
    team: Team,
    config: NodeConfig,
    args: argparse.Namespace,
    positional: list[Any],
    kwargs: dict[str, Any],
) -> int:
    from ._node import Node

    async with Node(
        f"cli-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        try:
            await node.team.wait_for({args.robot}, timeout=args.wait)
        except TimeoutError:
            seen = ", ".join(sorted(node.team.members())) or "none"
            print(
                f"mover call: no member {args.robot!r} in team {team.name!r} "
                f"(members seen: {seen})",
                file=sys.stderr,
            )
            return 1
        try:
            result = await node.call(
                args.robot, args.procedure, *positional, timeout=args.timeout, **kwargs
            )
        except (CallError, WireError) as exc:  # WireError: an argument msgpack cannot carry
            print(f"mover call: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 1
    print(json.dumps(result, default=_plain))
    return 0


def _plain(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, bytes):
        return value.hex()
    raise TypeError(f"cannot show a {type(value).__name__}")


# -- keygen ---------------------------------------------------------------------------------------


def register_keygen(sub: Sub) -> None:
    """Add ``mover keygen``."""
    p = sub.add_parser("keygen", help="make a new team key")
    p.add_argument("--team", required=True)
    p.add_argument("--out", metavar="FILE", help="write the key (hex) to FILE, mode 600")
    p.set_defaults(func=run_keygen)


def run_keygen(args: argparse.Namespace) -> int:
    try:
        team = Team.generate(args.team)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if args.out:
        import os

        try:
            fd = os.open(args.out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        except OSError as exc:
            raise UsageError(f"cannot write {args.out}: {exc.strerror or exc}") from None
        with os.fdopen(fd, "w") as f:
            f.write(team.key.hex() + "\n")
        print(f"export MOVER_TEAM={team.name} MOVER_TEAM_KEY_FILE={args.out}")
    else:
        print(f"export MOVER_TEAM={team.name} MOVER_TEAM_KEY={team.key.hex()}")
    return 0


# -- run ------------------------------------------------------------------------------------------


def register_run(sub: Sub) -> None:
    """Add ``mover run``."""
    p = sub.add_parser(
        "run",
        help="start an installed program on members of a team",
        description="Starts PROGRAM on every chosen member (no code is sent: "
        "members run their installed copy), shows progress, and prints each "
        "member's outcome. The launcher is not a coordinator: with --detach it "
        "exits once the run has started.",
    )
    p.add_argument("program")
    p.add_argument(
        "--robots",
        help="comma-separated members (default: every member that is not a tool or a world)",
    )
    p.add_argument(
        "--args", metavar="JSON", default="{}", help="the program's arguments as a JSON object"
    )
    p.add_argument("--detach", action="store_true", help="exit once the run has started")
    p.add_argument("--run-id", type=member_name, help="name of the run (default: PROGRAM-<random>)")
    _team_options(p)
    p.set_defaults(func=run_run)


def run_run(args: argparse.Namespace) -> int:
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


async def _run(
    team: Team,
    config: NodeConfig,
    args: argparse.Namespace,
    robots: list[str] | None,
    kwargs: dict[str, Any],
) -> int:
    import time

    from ._node import Node
    from ._programs import PROGRESS_TOPIC, launch

    run = args.run_id or f"{args.program}-{secrets.token_hex(3)}"
    async with Node(
        f"run-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        try:
            if robots:
                await node.team.wait_for(robots, timeout=args.wait)
            else:
                await asyncio.sleep(args.wait)
        except TimeoutError:
            missing = sorted(set(robots or ()) - node.team.members())
            print(f"mover run: not in team {team.name!r}: {', '.join(missing)}", file=sys.stderr)
            return 1
        members = robots or sorted(
            n
            for n in node.team.members()
            if (i := node.team.info(n)) is not None and i.kind not in ("tool", "world")
        )
        if not members:
            print(f"mover run: no members in team {team.name!r}", file=sys.stderr)
            return 1
        progress = node.subscribe(f"{PROGRESS_TOPIC}/{run}")
        started = time.monotonic()

        async def show() -> None:
            async for m in progress:
                info = {k: v for k, v in m.data.items() if k not in ("member", "phase")}
                extra = " ".join(f"{k}={_short(v)}" for k, v in info.items())
                print(
                    f"[{time.monotonic() - started:6.1f}s] {m.data.get('member')}: "
                    f"{m.data.get('phase')} {extra}".rstrip(),
                    flush=True,
                )

        shower = asyncio.create_task(show())
        print(f"run {run}: {args.program} on {', '.join(members)}", flush=True)
        try:
            outcomes = await launch(
                node, args.program, members, kwargs, run=run, wait=not args.detach
            )
        except CallError as exc:
            print(f"mover run: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 1
        finally:
            await asyncio.sleep(0.1)
            shower.cancel()
    if args.detach:
        print(f"run {run} started; the members go on without this launcher")
        return 0
    failed = 0
    for member, outcome in outcomes.items():
        if "error" in outcome:
            failed += 1
            print(f"{member}: FAILED {outcome['error']}")
            if outcome.get("traceback"):  # a bug in the program: where it happened
                print("  " + outcome["traceback"].rstrip().replace("\n", "\n  "))
        else:
            print(f"{member}: {json.dumps(outcome.get('result'), default=_plain)}")
    return 1 if failed else 0


def _short(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.2f}"
    if isinstance(value, list) and all(isinstance(v, float) for v in value):
        return "[" + ", ".join(f"{v:.2f}" for v in value) + "]"
    return str(value)
