"""`mover robot` (and ``python -m robots``): start one robot process.

The hardware backend is chosen by name (``--hardware``: an installed ``mover.hardware`` entry
point, or ``none`` for a workstation) and its options pass through untouched: ``--world NAME``
is the option ``world``, and ``--option KEY=VALUE`` (repeatable) any option, its value parsed as
JSON when it parses (``3``, ``0.5``, ``true``, ``"text"``), else kept as the string given. The
backend says which options it takes (``robots.backend``); any other is a one-line usage error.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mover import ConfigError, NameTaken
from mover.cli import (
    Terminated,
    UsageError,
    add_command,
    add_log_arguments,
    add_team_arguments,
    interrupt_on_sigterm,
    json_object,
    setup_logging,
    team_from_args,
)

from .process import NO_HARDWARE, run_robot


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The robot process's options (the logging options are the caller's: ``mover`` has them)."""
    p.add_argument("--name", required=True, help="the robot's name in the team")
    add_team_arguments(p)
    p.add_argument("--kind", help="the robot's kind (default: from --team-file, else 'robot')")
    p.add_argument(
        "--hardware",
        default="sim",
        help="hardware backend, a mover.hardware entry point (sim: the continuous world "
        f"process, grid: the grid world process), or {NO_HARDWARE} (a workstation); "
        "default sim",
    )
    p.add_argument(
        "--world",
        default=None,
        metavar="NAME",
        help="name of the world process: the backend's option 'world' (each backend has a "
        "default: sim 'world', grid 'gridworld')",
    )
    p.add_argument(
        "--option",
        action="append",
        metavar="KEY=VALUE",
        help="a backend option (e.g. call_timeout=60); VALUE is JSON if it parses, else a "
        "string; repeatable",
    )
    p.add_argument("--spec", metavar="JSON", help="the robot's body and devices, as JSON")
    p.add_argument(
        "--team-file",
        metavar="TOML",
        help="a team file: [[robots]] entries with name, kind and spec",
    )


def backend_options(world: str | None, items: Sequence[str]) -> dict[str, Any]:
    """The backend options of ``--world`` and of each ``--option KEY=VALUE``.

    A VALUE that parses as JSON is that value; any other is the string itself. Raises
    :class:`~mover.cli.UsageError` for an item without ``KEY=`` or a key given twice.
    """
    options: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"--option {item!r}: expected KEY=VALUE")
        if key in options:
            raise UsageError(f"--option {key}= is given twice")
        try:
            options[key] = json.loads(text)
        except json.JSONDecodeError:
            options[key] = text
    if world is not None:
        if "world" in options:
            raise UsageError("the world is given twice: --world and --option world=")
        options["world"] = world
    return options


def register_robot(sub: Any) -> None:
    """Add ``mover robot``."""
    add_arguments(add_command(sub, "robot", run, "run one robot process"))


def _member(path: str, name: str) -> dict[str, Any]:
    try:
        data = tomllib.loads(Path(path).read_bytes().decode("utf-8"))
    except UnicodeDecodeError:
        raise UsageError(f"team file {path}: not UTF-8") from None
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise UsageError(f"team file {path}: {exc}") from None
    robots = data.get("robots", [])
    if not isinstance(robots, list):
        raise UsageError(f"team file {path}: 'robots' must be an array of tables")
    for i, entry in enumerate(robots):
        if not isinstance(entry, dict) or "name" not in entry:
            raise UsageError(f"team file {path}: robots[{i}] needs a name")
        if entry["name"] == name:
            return entry
    raise UsageError(f"team file {path}: no robot named {name!r}")


def run(args: argparse.Namespace) -> int:
    """Run one robot process, as its options say, until interrupted (Ctrl-C or SIGTERM)."""
    entry: dict[str, Any] = _member(args.team_file, args.name) if args.team_file else {}
    spec = dict(entry.get("spec", {}))
    if args.spec:
        spec.update(json_object(args.spec, "--spec"))
    team, config = team_from_args(args)
    kind = args.kind or entry.get("kind", "robot")
    options = backend_options(args.world, args.option or ())
    try:
        asyncio.run(
            run_robot(
                args.name,
                team=team,
                config=config,
                kind=kind,
                hardware=args.hardware,
                spec=spec,
                options=options,
                ready=lambda: print("READY", flush=True),
            )
        )
    except (ValueError, NameTaken) as exc:  # found before anything starts
        raise UsageError(str(exc)) from None
    return 0


def main() -> int:
    """``python -m robots``."""
    p = argparse.ArgumentParser(prog="python -m robots", description="run one robot process")
    add_arguments(p)
    add_log_arguments(p)
    args = p.parse_args()
    interrupt_on_sigterm()
    try:
        setup_logging(args, default="INFO")
        return run(args)
    except (UsageError, ConfigError) as exc:
        print(f"robots: {exc}", file=sys.stderr)
        return 2
    except Terminated:
        return 143
    except KeyboardInterrupt:
        return 130
