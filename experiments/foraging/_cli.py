"""`mover experiment foraging`: its command line, the settings it makes of it, and the run."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

from mover.cli import UsageError
from robots.foraging import TRAIL_COLOURS

from .._common import add_run_arguments, comma_list, read_run_arguments, runner_parser
from .._figures import add_figure_arguments
from ._model import load_times, model_rows, paper_times, pooled, report
from ._paper import PAPER_T1, PAPER_T2, PAPER_T3
from ._plots import Chart, plot
from ._report import no_nan, table1, table2, table3
from ._settings import TABLES, ForagingSettings
from ._trial import Row, table1_rows, table2_rows, table3_rows


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``foraging`` experiment to ``mover experiment``."""
    from . import __doc__ as doc

    p = runner_parser(sub, "foraging", "Simonin et al. c-marking foraging tables 1-3, Fig. 9", doc)
    p.add_argument(
        "--table",
        choices=TABLES,
        default="all",
        help="which table (ants = Figure 9, c-marking vs ants; model = the T = a*D + b*TB fit of "
        "Tables 1-3); default all (not the model)",
    )
    add_run_arguments(p, runs=None, seed=2007, runs_default="until the SE is <= 5 %% of the mean")
    p.add_argument("--min-runs", type=int, default=30, help="adaptive mode: at least (30)")
    p.add_argument("--max-runs", type=int, default=1000, help="adaptive mode: at most (1000)")
    p.add_argument(
        "--agents",
        type=comma_list(int),
        default=None,
        help="comma-separated agent counts for tables 1/2 (default: the paper's)",
    )
    p.add_argument(
        "--sizes",
        type=comma_list(int),
        default=None,
        help="comma-separated sides for table 3 / ants (default 12,25,50,100,200)",
    )
    p.add_argument(
        "--max-iterations",
        type=int,
        default=200_000,
        help="a run still going after this is counted unfinished (200000)",
    )
    p.add_argument(
        "--until",
        choices=["exhausted", "delivered"],
        default="exhausted",
        help="end of a run: resources exhausted (paper, 5.1) or also delivered",
    )
    p.add_argument(
        "--literal",
        action="store_true",
        help="c-marking exactly as Algorithm 4 (no removal of dead-end trails)",
    )
    p.add_argument(
        "--forget-at-base",
        action="store_true",
        help="c-marking variant: climb straight back the trail just come down",
    )
    p.add_argument(
        "--colour-on-move",
        action="store_true",
        help="c-marking variant: colour only cells moved into, not the source cell",
    )
    p.add_argument(
        "--trail-colours",
        choices=TRAIL_COLOURS,
        default="single",
        help="c-marking reading: one trail colour (single, default) or one colour per trail, "
        "so that removing a trail leaves the trails merged with it whole",
    )
    p.add_argument(
        "--climb-any",
        action="store_true",
        help="c-marking variant: climb the highest coloured new neighbour, up or not (the letter)",
    )
    p.add_argument(
        "--agent-seeds",
        type=int,
        default=1,
        help="agent seeds per environment (common random numbers; the SE is then over "
        "environments); default 1",
    )
    p.add_argument(
        "--fit",
        action="append",
        default=[],
        metavar="LABEL=FILE[,FILE...]",
        help="--table model: also fit our times stored in these runner outputs (repeatable)",
    )
    p.add_argument("--json", action="store_true", help="end with one JSON line of every mean")
    add_figure_arguments(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


MAX_AGENTS = 10_000
MAX_SIZE = 1000


def settings(args: argparse.Namespace) -> ForagingSettings:
    """The settings the command line asks for, checked; raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    given = read_run_arguments(args)
    if not 1 <= args.min_runs <= args.max_runs:
        raise UsageError("--min-runs must be positive and at most --max-runs")
    if min(args.agents or [1]) < 1 or min(args.sizes or [5]) < 5:
        raise UsageError("--agents must be positive and --sizes at least 5 (20 resources)")
    if max(args.agents or [1]) > MAX_AGENTS or max(args.sizes or [5]) > MAX_SIZE:
        raise UsageError(f"--agents must be at most {MAX_AGENTS} and --sizes at most {MAX_SIZE}")
    if args.max_iterations < 1:
        raise UsageError("--max-iterations must be positive")
    if args.agent_seeds < 1:
        raise UsageError("--agent-seeds must be positive")
    if args.trail_colours == "per-trail" and args.colour_on_move:
        raise UsageError("--trail-colours per-trail needs the source cell coloured: "
                         "not with --colour-on-move")  # fmt: skip
    fits = []
    for item in args.fit:
        label, eq, files = item.partition("=")
        if not eq or not label or not files:
            raise UsageError(f"--fit {item!r}: LABEL=FILE[,FILE...]")
        missing = [f for f in files.split(",") if not Path(f).is_file()]
        if missing:
            raise UsageError(f"--fit {label}: no file {missing[0]}")
        fits.append((label, tuple(files.split(","))))
    return ForagingSettings(
        seed=given.seed,
        table=args.table,
        runs=given.runs,
        min_runs=args.min_runs,
        max_runs=args.max_runs,
        agents=tuple(args.agents or ()),
        sizes=tuple(args.sizes or ()),
        max_iterations=args.max_iterations,
        until=args.until,
        literal=args.literal,
        forget_at_base=args.forget_at_base,
        colour_on_move=args.colour_on_move,
        trail_colours=args.trail_colours,
        climb_any=args.climb_any,
        agent_seeds=args.agent_seeds,
        fit=tuple(fits),
        out=None if args.no_plots else Path(args.out),
        format=args.format,
        quiet=args.quiet,
        json=args.json,
    )


def run(args: argparse.Namespace) -> int:
    """Run the selected tables, print them beside the paper's, write plots, maybe JSON."""
    s = settings(args)
    out: dict[str, Any] = {"seed": s.seed, "runs": s.runs or "auto", "until": s.until,
                 "literal": s.literal, "forget_at_base": s.forget_at_base,
                 "colour_on_move": s.colour_on_move} | s.reading  # fmt: skip
    t0 = time.perf_counter()
    steps = 0
    reading = "".join(f", {k} {v}" for k, v in s.reading.items())
    print(
        f"foraging experiment: seed {s.seed}, runs "
        f"{s.runs or f'auto (SE <= 5 % of the mean, {s.min_runs}..{s.max_runs})'}{reading}"
    )
    plots = []
    for t in s.tables:
        text, figures, rows, path = _table(t, s)
        print(text)
        out.update(figures)
        plots.append(path)
        steps += sum(r.agent_steps for r in rows)
        sec = sum(r.seconds for r in rows)
        print(
            f"speed: {sum(r.agent_steps for r in rows) / max(sec, 1e-9):,.0f} agent-steps/s"
            f" over {sec:.1f} s"
        )
    elapsed = time.perf_counter() - t0
    print(
        f"\ntotal: {steps:,} agent-steps in {elapsed:.1f} s = {steps / elapsed:,.0f} "
        f"agent-steps/s; plots: {', '.join(str(p) for p in plots if p)}"
    )
    if s.json:
        print(json.dumps(no_nan(out), allow_nan=False))
    return 0


def _table(t: str, s: ForagingSettings) -> tuple[str, dict[str, Any], list[Row], Path | None]:
    """Measure table ``t``; its text, its figures, its rows and its plot."""
    if t == "model":
        texts, figures, rows, every = [], {}, [], {}
        for table in (1, 2, 3):
            every[table] = measured = model_rows(s, table)
            ours = {label: load_times(files, table) for label, files in s.fit}
            text, fig = report(table, measured, {k: v for k, v in ours.items() if v}, s.seed)
            texts.append(text)
            figures.update(fig)
            rows += [r.d for r in measured]
        texts.append("\nOne (a, b) for all three tables:")
        texts.append(pooled(every, {t: paper_times(t) for t in every}).replace("pooled", "paper"))
        for label, files in s.fit:
            ours_all = {t: load_times(files, t) for t in every}
            texts.append(pooled(every, ours_all).replace("pooled", label))
        return "\n".join(texts), figures, rows, None
    if t == "1":
        xs, rows = table1_rows(s)
        text, figures = table1(xs, rows, s.seed)
        series = {
            "paper": [PAPER_T1.get(n, (math.nan,))[0] for n in xs],
            "ours": [r.mean for r in rows],
        }
        errors = {"ours": [r.stats.se for r in rows]}
        chart = Chart("table1", xs, series, errors, "agents", "Table 1 (Setup 1)")
        return text, figures, rows, _plot(s, chart)
    if t == "2":
        xs, rows = table2_rows(s)
        text, figures = table2(xs, rows, s.seed)
        vref = rows[0].mean * xs[0]
        series = {
            "paper measured": [PAPER_T2.get(n, (math.nan,))[0] for n in xs],
            "ours measured": [r.mean for r in rows],
            "ours projected V_ref/n": [vref / n for n in xs],
        }
        errors = {"ours measured": [r.stats.se for r in rows]}
        chart = Chart("table2", xs, series, errors, "agents", "Table 2 (Setup 2)")
        return text, figures, rows, _plot(s, chart)
    sizes, got = table3_rows(s, ("cmarking", "ants") if t == "ants" else ("cmarking",))
    text, figures = table3(sizes, got, s.seed)
    cells = [z * z for z in sizes]
    series = {"paper c-marking": [PAPER_T3.get(round(math.sqrt(x)), math.nan) for x in cells]}
    series.update({f"ours {k}": [r.mean for r in v] for k, v in got.items()})
    errors = {f"ours {k}": [r.stats.se for r in v] for k, v in got.items()}
    name = "fig9" if t == "ants" else "table3"
    rows = [r for rs in got.values() for r in rs]
    title = "Table 3 (Setup 3), 50 agents"
    return text, figures, rows, _plot(s, Chart(name, cells, series, errors, "cells", title))


def _plot(s: ForagingSettings, chart: Chart) -> Path | None:
    return None if s.out is None else plot(s.out, chart, s.format)
