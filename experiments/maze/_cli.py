"""`mover experiment maze`: its command line, the settings it makes of it, and the run."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from mover.cli import UsageError
from robots.explore import EXCHANGES, METHODS, NEWS, PARTITIONS
from sim_hw.grid import MazeFileError, load_maze

from .._common import (
    add_list_arguments,
    add_run_arguments,
    comma_list,
    read_run_arguments,
    runner_parser,
)
from .._figures import add_figure_arguments
from .._saved import add_executor_argument
from ._paper import AGENT_COUNTS, PROBABILITIES, SIZE
from ._report import composite, composite_text, tables
from ._settings import MazeSettings
from ._trial import trials


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``maze`` experiment runner."""
    from . import __doc__ as doc

    help = "CU-LVP and baselines on seeded mazes (Linardakis et al., IV-V)"
    parser = runner_parser(sub, "maze", help, doc)
    add_run_arguments(parser, runs=100, seed=None, workers=1)
    add_executor_argument(parser)
    parser.add_argument(
        "--save",
        type=Path,
        default=None,
        help="per-point JSON-lines directory, read back and added to (default: keep nothing)",
    )
    parser.add_argument(
        "--hedac-runs",
        type=int,
        default=None,
        help="fewer runs for HEDAC, the slow method (default: --runs)",
    )
    add_list_arguments(
        parser,
        ("--methods", comma_list(str, METHODS), METHODS, f"comma list of {', '.join(METHODS)}"),
        (
            "--agents",
            comma_list(int),
            AGENT_COUNTS,
            "comma list of agent counts (default 1,2,4,6,8,10,15,20)",
        ),
    )
    parser.add_argument("--size", type=int, default=SIZE, help="nominal maze size (default 30)")
    add_list_arguments(
        parser,
        (
            "--p",
            comma_list(float),
            PROBABILITIES,
            "comma list of obstacle probabilities (default 0.85,0.15)",
        ),
    )
    parser.add_argument(
        "--exchanges",
        type=int,
        default=EXCHANGES,
        help=f"map exchanges per round (default {EXCHANGES}: two relay hops;"
        " 1: the paper's single exchange)",
    )
    parser.add_argument(
        "--partition",
        choices=PARTITIONS,
        default="balanced",
        help="CU-LVP's regions: balanced (default: about equal sizes) or voronoi (the plain"
        " partition, as before)",
    )
    parser.add_argument(
        "--news",
        choices=NEWS,
        default="on",
        help="CU-LVP's agents pass on each other's latest news: what changed since their last"
        " message (default on); whole: all of it in every message (as before 2026-12-04"
        " 15:30 UTC); off: CU-LVP as before 2026-12-04 (no news passed on; helpers neither share"
        " a region's work by it nor choose their region again)",
    )
    parser.add_argument("--maze", type=Path, default=None, help="run on this maze JSON file")
    add_figure_arguments(parser)
    parser.add_argument(
        "--load",
        type=Path,
        action="append",
        default=[],
        metavar="FILE",
        help="tabulate the runs saved by earlier --json runs instead of running"
        " (repeatable; the last line of each file is read)",
    )
    parser.add_argument(
        "--json", action="store_true", help="end with one JSON line holding every run's figures"
    )
    parser.set_defaults(func=run)


def settings(args: argparse.Namespace) -> MazeSettings:
    """The settings the command line asks for, checked; the maze file read. Raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    given = read_run_arguments(args)
    if min(args.agents) < 1 or args.exchanges < 1:
        raise UsageError("--agents and --exchanges must be positive")
    if not 4 <= args.size <= 1000:
        raise UsageError(f"--size must be from 4 to 1000, got {args.size}")
    if not all(0.0 <= p <= 1.0 for p in args.p):  # NaN too
        raise UsageError(f"--p must be probabilities in [0, 1], got {args.p}")
    maze = None
    if args.maze is not None:
        try:
            maze = load_maze(args.maze)
        except MazeFileError as exc:
            raise UsageError(str(exc)) from None
        if max(args.agents) > len(maze.starts):
            raise UsageError(
                f"{args.maze} has {len(maze.starts)} starts, {max(args.agents)} agents asked"
            )
    return MazeSettings(
        seed=given.seed,
        runs=args.runs,
        hedac_runs=args.runs if args.hedac_runs is None else args.hedac_runs,
        methods=tuple(args.methods),
        agents=tuple(args.agents),
        size=args.size,
        p=tuple(args.p),
        exchanges=args.exchanges,
        partition=args.partition,
        news=args.news,
        maze=maze,
        maze_path=args.maze,
        out=None if args.no_plots else args.out,
        format=args.format,
        load=tuple(args.load),
        json=args.json,
        save=args.save,
        workers=given.workers,
        executor=args.executor,
    )


def run(args: argparse.Namespace) -> int:
    """Run the experiment; print the seed, the tables and the composite index."""
    s = settings(args)
    if s.load:
        return _report_saved(s)
    print(f"seed: {s.seed}")
    print(
        f"methods: {','.join(s.methods)}  agents: {','.join(map(str, s.agents))}  "
        f"runs: {s.runs} (hedac {s.runs_for('hedac')})  "
        + (f"maze: {s.maze_path}" if s.maze_path else f"size: {s.size}  p: {list(s.p)}")
        + f"  exchanges: {s.exchanges}  partition: {s.partition}"
        + ("" if s.news == "on" else f"  news: {s.news}")
    )
    records = trials(s)
    _report(records, list(s.methods), list(s.agents), s)
    if s.json:
        print(json.dumps({"seed": s.seed, "size": s.size, "runs": records}))
    return 0


def _report_saved(s: MazeSettings) -> int:
    records: list[dict[str, Any]] = []
    for path in s.load:
        try:
            data = json.loads(path.read_text().strip().splitlines()[-1])
        except (OSError, ValueError, IndexError) as exc:
            raise UsageError(f"{path}: no JSON line of runs: {exc}") from None
        print(f"loaded {path}: seed {data['seed']}, {len(data['runs'])} runs")
        records.extend(
            r for r in data["runs"] if r["method"] in s.methods and r["agents"] in s.agents
        )
    methods = [m for m in s.methods if any(r["method"] == m for r in records)]
    agents = [n for n in s.agents if any(r["agents"] == n for r in records)]
    _report(records, methods, agents, s)
    return 0


def _report(
    records: list[dict[str, Any]], methods: list[str], agents: list[int], s: MazeSettings
) -> None:
    print(tables(records, methods, agents))
    scores = composite(records, methods, agents)
    print(composite_text(scores, agents))
    if s.out is not None:
        from ._plots import plots

        for path in plots(records, scores, methods, agents, s.out, s.format):
            print(f"wrote {path}")
