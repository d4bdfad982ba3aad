"""`mover experiment eyebot`: its command line, the settings it makes of it, and the run."""

from __future__ import annotations

import argparse
import json
import math
import time

from mover.cli import UsageError

from .._common import add_run_arguments, comma_list, read_run_arguments, runner_parser
from .._figures import add_figure_arguments
from .._saved import add_saved_arguments, seeds_table
from . import _report
from ._sweep import FIGURES, EyebotSettings, points, run_points

_TABLES = {
    "fig2": _report.fig2,
    "fig3": _report.fig3,
    "fig4": _report.fig4,
    "fig5": _report.fig5,
    "beyond": _report.beyond,
}
MAX_DURATION = 100_000.0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``eyebot`` experiment runner."""
    from . import __doc__ as doc

    help = "eye-bots guide foot-bots by stigmergy (Ducatelle et al., sections 5-7)"
    parser = runner_parser(sub, "eyebot", help, doc)
    parser.add_argument(
        "--figure",
        type=comma_list(str, FIGURES),
        default=["fig2"],
        help="comma list of fig2, fig3, fig4, fig5, beyond (default fig2)",
    )
    add_run_arguments(parser, runs=30, seed=None, workers=2)
    parser.add_argument(
        "--duration", type=float, default=3000.0, help="simulated seconds a run (default 3000)"
    )
    parser.add_argument(
        "--saved",
        action="store_true",
        help="report the saved runs of --seed only (at most --runs a point), making none; "
        "without --seed, list the seeds saved",
    )
    add_saved_arguments(parser, "eyebot")
    add_figure_arguments(parser)
    parser.set_defaults(func=run)


def settings(args: argparse.Namespace) -> EyebotSettings:
    """The settings the command line asks for, checked; raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    given = read_run_arguments(args)
    if not (math.isfinite(args.duration) and 10.0 <= args.duration <= MAX_DURATION):
        raise UsageError(f"--duration must be from 10 to {MAX_DURATION:g} s, got {args.duration}")
    save = None if args.no_save else args.save
    if args.saved and save is None:
        raise UsageError("--saved reports the saved runs: it cannot go with --no-save")
    if save is not None and args.duration != 3000.0:  # runs of other lengths are kept apart
        save = save.with_name(f"{save.name}-duration={args.duration:g}")
    return EyebotSettings(
        seed=given.seed,
        runs=args.runs,
        figures=tuple(args.figure),
        duration=args.duration,
        workers=given.workers,
        executor=args.executor,
        save=save,
        progress=not args.quiet,
        saved_only=args.saved,
    )


def run(args: argparse.Namespace) -> int:
    """Run the figures' points; print the seed, each figure's table, the speed."""
    s = settings(args)
    if s.saved_only and args.seed is None and s.save is not None:
        print(seeds_table(s.save))
        return 0
    print(f"seed: {s.seed}")
    print(f"figures: {','.join(s.figures)}  runs per point: {s.runs}  duration: {s.duration:g} s")
    if s.save is not None:
        print(f"runs saved in: {s.save}")
    if s.saved_only:
        print("saved runs only (--saved): the tables count the runs each point has")
    everything = []
    for figure in s.figures:
        t0 = time.monotonic()
        records, fresh, wall = run_points(s, points(figure), figure)
        everything.extend(records)
        print(_TABLES[figure](records))
        print(f"{figure}: {len(fresh)} runs made in {time.monotonic() - t0:.0f} s wall")
        if fresh:
            print(_report.speed(fresh, wall))
        if not args.no_plots:
            from ._plots import plot

            path = plot(figure, records, args.out, args.format)
            if path is not None:
                print(f"wrote {path}")
    if args.json:
        print(json.dumps({"seed": s.seed, "runs": everything}))
    return 0
