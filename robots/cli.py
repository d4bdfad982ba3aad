"""`mover robot` (and ``python -m robots``): start one robot process."""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import os
import sys
import tomllib
from pathlib import Path
from typing import Any

from mover import NodeConfig, Team

from .process import run_robot


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--name", required=True, help="the robot's name in the team")
    p.add_argument("--team", help="team name (default $MOVER_TEAM); key from $MOVER_TEAM_KEY")
    p.add_argument("--kind", help="the robot's kind (default: from --team-file, else 'robot')")
    p.add_argument(
        "--hardware",
        default="sim",
        help="hardware backend: sim (world process over zenoh), none (workstation)",
    )
    p.add_argument(
        "--world",
        default=None,
        help="name of the world process (sim: 'world', grid: 'gridworld' by default)",
    )
    p.add_argument("--spec", metavar="JSON", help="the robot's body and devices, as JSON")
    p.add_argument(
        "--team-file",
        metavar="TOML",
        help="a team file: [[robots]] entries with name, kind and spec",
    )
    p.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help="zenoh endpoint of a team member or router; repeatable",
    )


def register_robot(sub: Any) -> None:
    """Add ``mover robot``."""
    p = sub.add_parser("robot", help="run one robot process")
    add_arguments(p)
    p.set_defaults(func=run)


def _member(path: str, name: str) -> dict[str, Any]:
    from mover._cli import UsageError

    try:
        data = tomllib.loads(Path(path).read_text())
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
    from mover._cli import UsageError

    entry: dict[str, Any] = _member(args.team_file, args.name) if args.team_file else {}
    spec = dict(entry.get("spec", {}))
    if args.spec:
        try:
            spec.update(json.loads(args.spec))
        except json.JSONDecodeError as exc:
            raise UsageError(f"--spec is not JSON: {exc.msg}") from None
    try:
        team = Team.from_env(args.team)
        config = NodeConfig.from_env(args.connect or ())
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    kind = args.kind or entry.get("kind", "robot")
    options: dict[str, Any] = {}
    if args.hardware == "sim":
        options = {"world": args.world or "world"}
    elif args.hardware == "grid" and args.world:
        options = {"world": args.world}
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
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return 0


def main() -> int:
    """``python -m robots``."""
    p = argparse.ArgumentParser(prog="python -m robots", description="run one robot process")
    add_arguments(p)
    args = p.parse_args()
    level = os.environ.get("MOVER_LOG_LEVEL", "INFO").upper()
    logging.basicConfig(level=level, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    from mover._cli import UsageError

    try:
        return run(args)
    except UsageError as exc:
        print(f"robots: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
