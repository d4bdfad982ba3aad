"""The `mover ps`, `mover call`, `mover echo` and `mover keygen` verbs (`mover run`, `runs`
and `cancel` are in ``mover.cli._runs``).

Team and transport come from ``--team`` and the MOVER_* environment (see ``mover._config``);
``--connect`` adds endpoints to reach the team. Both are :func:`mover.cli.add_team_arguments`'.
``mover ps`` shows each member's run and phase from its ``mover.status`` (one call per member,
bounded by ``STATUS_TIMEOUT``).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import logging
import math
import secrets
import sys
import time
from collections.abc import Callable, Coroutine
from typing import TYPE_CHECKING, Any

from .. import _keys
from .._config import NodeConfig, TeamCredentials
from .._exceptions import CallError, NotDelivered, UnknownProcedure, WireError
from .._keys import check_name
from . import (
    UsageError,
    add_command,
    add_team_arguments,
    bounded,
    json_argument,
    json_object,
    positive,
    team_from_args,
)

if TYPE_CHECKING:
    from .._node import Node

    Sub = argparse._SubParsersAction[argparse.ArgumentParser]
    TeamVerb = Callable[
        [TeamCredentials, NodeConfig, argparse.Namespace], Coroutine[object, object, int]
    ]

log = logging.getLogger("mover.cli")

MAX_WAIT = 3600.0  # seconds a verb may be asked to wait for the team
ECHO_QUEUE = 1000  # messages mover echo keeps unread at most
STATUS_TIMEOUT = 3.0  # seconds a member has to answer mover.status
SETTLE = 0.3  # seconds between a peer's queries for the team's members (see discover)
NO_ANSWER = "(no answer)"
NO_PROGRAMS = "-"  # a member that hosts no programs (a world, a tool)


def _team_options(p: argparse.ArgumentParser) -> None:
    add_team_arguments(p)
    p.add_argument(
        "--wait",
        type=bounded(float, 0.0, MAX_WAIT, above=True),
        default=2.0,
        metavar="S",
        help="seconds to wait at most for the team to be discovered (default 2, at most 3600)",
    )


def _on_team(verb: TeamVerb) -> Callable[[argparse.Namespace], int]:
    """An argparse ``func`` that reads the team from the options and runs ``verb`` on it."""

    def run(args: argparse.Namespace) -> int:
        team, config = team_from_args(args)
        return asyncio.run(verb(team, config, args))

    run.__doc__ = verb.__doc__

    return run


def _listing(sub: Sub, name: str, help: str, json_help: str, verb: TeamVerb) -> None:
    """Add a verb that lists what it observes of a team: the team's options and ``--json``."""
    p = sub.add_parser(name, help=help)
    _team_options(p)
    p.add_argument("--json", action="store_true", help=json_help)
    p.set_defaults(func=_on_team(verb))


# -- ps -------------------------------------------------------------------------------------------


def register_ps(sub: Sub) -> None:
    """Add ``mover ps``."""
    _listing(sub, "ps", "list the live members of a team", "one JSON object per member", _ps)


async def _ps(team: TeamCredentials, config: NodeConfig, args: argparse.Namespace) -> int:
    rows, statuses = await observe(team, config, args.wait, "ps")
    if args.json:
        for i in rows:
            status = statuses.get(i.name, NO_PROGRAMS)
            runs = [_brief(r) for r in _running(status)] if isinstance(status, list) else status
            print(
                json.dumps(
                    {
                        "name": i.name,
                        "kind": i.kind,
                        "uptime_s": round(i.uptime, 1),
                        "pid": i.pid,
                        "host": i.host,
                        "runs": runs,
                    }
                )
            )
        return 0
    if not rows:
        print(f"no members of team {team.name!r} seen within {args.wait} s", file=sys.stderr)
        return 1
    print(f"{'NAME':<16} {'KIND':<12} {'UPTIME':>10} {'PID':>8}  {'RUN':<24} {'PHASE':<12} HOST")
    for i in rows:
        status = statuses.get(i.name, NO_PROGRAMS)
        if isinstance(status, list):
            running = _running(status)
            run = ",".join(r["run"] for r in running) or "idle"
            phase = ",".join(str(r.get("phase", "")) for r in running) or "-"
        else:
            run, phase = status, "-"
        print(
            f"{i.name:<16} {i.kind:<12} {_duration(i.uptime):>10} {i.pid:>8}  "
            f"{run:<24} {phase:<12} {i.host}"
        )
    return 0


async def observe(
    team: TeamCredentials, config: NodeConfig, wait: float, tag: str
) -> tuple[list[Any], dict[str, list[dict[str, Any]] | str]]:
    """The team's members as an observer (not a member) sees them, and each one's
    ``mover.status`` (tools are not asked). Who is there comes from one liveliness query, then
    each holder's hello; ``wait`` bounds both (a member that does not answer in time is left
    out), nothing waits longer than they take."""
    from .._node import Node

    async with Node(
        f"{tag}-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        await discover(node, wait)
        infos = [node.membership.info(n) for n in sorted(node.membership.members())]
        rows = [i for i in infos if i is not None]
        statuses = await _statuses(node, [i.name for i in rows if i.kind != "tool"])
    return rows, statuses


async def discover(node: Node, wait: float) -> None:
    """Return once ``node`` knows every member there is now, or after ``wait`` seconds with
    those it knows. Who is there: one liveliness query for the token holders (a router answers
    for the whole team), then their hellos. A peer links to the other peers one by one as it
    hears of them, and a query reaches only those it has linked to: as a peer, ask again until
    the answer has held still for :data:`SETTLE` seconds."""
    deadline = time.monotonic() + wait
    holders = await alive(node, wait)
    if node.config.mode != "client":
        still = time.monotonic()
        while (now := time.monotonic()) < deadline and now - still < SETTLE:
            await asyncio.sleep(min(SETTLE / 3, deadline - now))
            again = await alive(node, max(0.0, deadline - time.monotonic()))
            if not again <= holders:
                holders |= again
                still = time.monotonic()
    with contextlib.suppress(TimeoutError):
        await node.membership.wait_for(holders, timeout=max(0.0, deadline - time.monotonic()))


async def alive(node: Node, timeout: float) -> set[str]:
    """The names of the token holders of ``node``'s team now: one liveliness query, bounded."""
    from .._bridge import run_blocking

    session, key = node.zenoh_session, _keys.alive(node.team_name, "*")

    def ask() -> set[str]:
        replies = session.liveliness().get(key, timeout=timeout)
        return {_keys.robot_of(str(r.ok.key_expr)) for r in replies if r.ok is not None}

    names: set[str] = await run_blocking(ask)
    return names


async def _statuses(node: Node, members: list[str]) -> dict[str, list[dict[str, Any]] | str]:
    """Each member's ``mover.status`` (one call each, at once, bounded): its runs, or
    ``NO_ANSWER``, or ``NO_PROGRAMS`` for a member that hosts none."""

    async def one(member: str) -> list[dict[str, Any]] | str:
        try:
            runs = await node.call(member, "mover.status", timeout=STATUS_TIMEOUT)
        except UnknownProcedure:
            return NO_PROGRAMS
        except (NotDelivered, CallError, WireError):
            return NO_ANSWER
        if not isinstance(runs, list):
            return NO_ANSWER
        return [r for r in runs if isinstance(r, dict) and isinstance(r.get("run"), str)]

    answers = await asyncio.gather(*(one(m) for m in members))
    return dict(zip(members, answers, strict=True))


def _running(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [r for r in runs if r.get("state") == "running"]


def _brief(run: dict[str, Any]) -> dict[str, Any]:
    return {k: run.get(k) for k in ("run", "program", "phase", "state")}


def _duration(seconds: float) -> str:
    s = int(seconds)
    return f"{s // 3600}h{s % 3600 // 60:02d}m" if s >= 3600 else f"{s // 60}m{s % 60:02d}s"


# -- call -----------------------------------------------------------------------------------------


def register_call(sub: Sub) -> None:
    """Add ``mover call``."""
    p = add_command(
        sub,
        "call",
        run_call,
        "call a robot's exported procedure",
        "Arguments are JSON values: 3, 1.5, '\"text\"', '[1, 2]'.",
    )
    p.add_argument("robot")
    p.add_argument("procedure", nargs="?", help="the procedure (not with --list)")
    p.add_argument("args", nargs="*", metavar="JSON", help="positional arguments, each JSON")
    p.add_argument(
        "--list",
        action="store_true",
        help="list the robot's exported procedures, their signatures and what they do",
    )
    p.add_argument(
        "--all",
        action="store_true",
        help="with --list: also mover's own protocol procedures (mover.*)",
    )
    p.add_argument("--kwargs", metavar="JSON", help="keyword arguments as a JSON object")
    p.add_argument("--timeout", type=positive, default=10.0, help="seconds (default 10)")
    _team_options(p)


def run_call(args: argparse.Namespace) -> int:
    if args.list:
        if args.procedure is not None or args.args or args.kwargs:
            raise UsageError("--list takes no procedure and no arguments")
        args.procedure = "mover.procedures"
    elif args.all:
        raise UsageError("--all goes with --list")
    elif args.procedure is None:
        raise UsageError("name a procedure to call (or --list the robot's procedures)")
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
    team: TeamCredentials,
    config: NodeConfig,
    args: argparse.Namespace,
    positional: list[Any],
    kwargs: dict[str, Any],
) -> int:
    from .._node import Node

    async with Node(
        f"cli-{secrets.token_hex(3)}", team, kind="tool", config=config, observer=True
    ) as node:
        try:
            await node.membership.wait_for({args.robot}, timeout=args.wait)
        except TimeoutError:
            seen = ", ".join(sorted(node.membership.members())) or "none"
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
    if args.list and isinstance(result, dict):
        hidden = [n for n in result if n.startswith("mover.")] if not args.all else []
        for name in sorted(set(result) - set(hidden)):
            entry = result[name] if isinstance(result[name], dict) else {}
            doc = f"  {entry['doc']}" if entry.get("doc") else ""
            print(f"{name}{entry.get('signature', '(?)')}{doc}")
        if hidden:
            print(f"({len(hidden)} of mover's own procedures (mover.*) not shown: --all)")
        return 0
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
    p = add_command(sub, "keygen", run_keygen, "make a new team key")
    p.add_argument("--team", required=True)
    p.add_argument("--out", metavar="FILE", help="write the key (hex) to FILE, mode 600")


def run_keygen(args: argparse.Namespace) -> int:
    """Make a new key for --team and print the shell lines that give it to mover (with --out,
    the key goes to that file, mode 600, and the lines name the file)."""
    try:
        team = TeamCredentials.generate(args.team)
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


# -- echo -----------------------------------------------------------------------------------------


def register_echo(sub: Sub) -> None:
    """Add ``mover echo``."""
    p = add_command(sub, "echo", run_echo, "print the messages of a broadcast topic, decoded")
    p.add_argument("topic", help="the topic, as programs name it (e.g. mover/run/RUN, hello)")
    p.add_argument(
        "--at",
        type=_pose,
        metavar="X,Y[,HEADING]",
        help="listen from this place (metres, radians): range-limited messages within range"
        " reach it, with distance and bearing",
    )
    p.add_argument(
        "--count",
        type=bounded(int, 0, 1_000_000),
        default=0,
        help="stop after N messages (default: until Ctrl-C)",
    )
    p.add_argument("--json", action="store_true", help="one JSON object per message")
    _team_options(p)


def _pose(text: str) -> tuple[float, float, float]:
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y[,HEADING], got {text!r}") from None
    if len(parts) not in (2, 3) or not all(math.isfinite(v) for v in parts):
        raise argparse.ArgumentTypeError(f"expected X,Y[,HEADING] (finite), got {text!r}")
    return (parts[0], parts[1], parts[2] if len(parts) == 3 else 0.0)


def run_echo(args: argparse.Namespace) -> int:
    """Print each message on TOPIC as it comes: time, sender, distance and bearing (from --at),
    and its data as JSON. Range-limited broadcasts reach an echo only when it is given a place
    (--at) within their range, as they would a robot there."""
    if not args.topic or len(args.topic) > 200 or any(c in args.topic for c in "*$#?"):
        raise UsageError(f"not a topic: {args.topic!r} (no wildcards, at most 200 characters)")
    team, config = team_from_args(args)
    return asyncio.run(_echo(team, config, args))


async def _echo(team: TeamCredentials, config: NodeConfig, args: argparse.Namespace) -> int:
    from .._node import Node

    where = args.at
    locator = _Fixed(where) if where is not None else None
    async with Node(
        f"echo-{secrets.token_hex(3)}",
        team,
        kind="tool",
        config=config,
        observer=True,
        locator=locator,
    ) as node:
        seen = 0
        async with node.subscribe(args.topic, maxlen=ECHO_QUEUE) as messages:
            print(f"mover echo: listening on {args.topic!r} in team {team.name!r}", file=sys.stderr)
            quiet = asyncio.get_running_loop().call_later(
                ECHO_QUIET, _say_quiet, args.topic, where is None
            )
            try:
                async for msg in messages:
                    seen += 1
                    quiet.cancel()
                    print(_echoed(msg, args.json), flush=True)
                    if args.count and seen >= args.count:
                        break
            finally:
                quiet.cancel()
    return 0


ECHO_QUIET = 5.0
"""Seconds of silence after which ``mover echo`` says what it is waiting for, once."""


def _say_quiet(topic: str, nowhere: bool) -> None:
    hint = "; range-limited broadcasts reach it only --at a place within their range"
    hint = hint if nowhere else ""
    print(
        f"mover echo: nothing on {topic!r} for {ECHO_QUIET:g} s; still listening (a lock-step"
        f" world sends only while its robots tick{hint})",
        file=sys.stderr,
    )


class _Fixed:
    """A locator at a fixed place (``mover echo --at``)."""

    def __init__(self, pose: tuple[float, float, float]) -> None:
        self.pose = pose

    def position(self) -> tuple[float, float, float]:
        return self.pose


def _echoed(msg: Any, as_json: bool) -> str:
    data = json.dumps(msg.data, default=_plain)
    if as_json:
        return json.dumps(
            {
                "sent": msg.sent,
                "sender": msg.sender,
                "distance": msg.distance,
                "bearing": msg.bearing,
                "data": json.loads(data),
            }
        )
    stamp = time.strftime("%H:%M:%S", time.localtime(msg.sent))
    where = (
        f" {msg.distance:.2f} m at {math.degrees(msg.bearing or 0.0):+.0f}°"
        if msg.distance is not None
        else ""
    )
    return f"{stamp} {msg.sender}{where}: {data}"
