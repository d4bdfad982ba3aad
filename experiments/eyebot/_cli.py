"""`mover experiment eyebot`: its command line, the settings it makes of it, and the run."""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

from mover.cli import UsageError
from robots.stigmergic import Reading
from sim_hw.continuous import TICK

from .._common import add_run_arguments, comma_list, read_run_arguments, runner_parser
from .._runner import add_runner_tail, every_run, save_dir, sweep_made
from .._saved import seeds_table
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
    parser.add_argument(
        "--footbots",
        type=comma_list(int),
        default=[],
        help="comma list: only the points with these numbers of foot-bots (default all)",
    )
    parser.add_argument(
        "--ways",
        type=comma_list(str, ("learning", "shortest", "weigh")),
        default=[],
        help="comma list of learning, shortest, weigh: only the points where the eye-bots work"
        " so (default all)",
    )
    old = parser.add_argument_group(
        "old readings of the paper (each kept as an option; runs saved apart, the save folder's"
        " name gets what differs from the defaults)"
    )
    old.add_argument(
        "--eyebot-period",
        type=float,
        default=TICK,
        help=f"seconds between two eye-bot steps (default {TICK:g}, the simulator's control"
        " step; the old reading: 1)",
    )
    old.add_argument(
        "--theta-f",
        choices=[r.value for r in Reading],
        default=Reading.APPROACHING.value,
        help="which foot-bots an eye-bot learns θ_f from: approaching (default: those coming"
        " towards it) or any (the old reading: every one in view, leaving ones too)",
    )
    old.add_argument(
        "--head-on",
        choices=["random", "right"],
        default="random",
        help="which way a foot-bot passes an obstacle straight ahead: random (default, a seeded"
        " coin) or right (the old rule)",
    )
    old.add_argument(
        "--eyebots-over-walls",
        action="store_true",
        help="the old cluttered arena: 28 eye-bots, 4 of them over its walls (default 24)",
    )
    add_runner_tail(parser, "eyebot", run)


def settings(args: argparse.Namespace) -> EyebotSettings:
    """The settings the command line asks for, checked; raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    given = read_run_arguments(args)
    if not (math.isfinite(args.duration) and 10.0 <= args.duration <= MAX_DURATION):
        raise UsageError(f"--duration must be from 10 to {MAX_DURATION:g} s, got {args.duration}")
    save = save_dir(args)
    if args.saved and save is None:
        raise UsageError("--saved reports the saved runs: it cannot go with --no-save")
    if not (math.isfinite(args.eyebot_period) and TICK - 1e-9 <= args.eyebot_period <= 60.0):
        raise UsageError(f"--eyebot-period must be from {TICK:g} to 60 s, got {args.eyebot_period}")
    if save is not None and args.duration != 3000.0:  # runs of other lengths are kept apart
        save = save.with_name(f"{save.name}-duration={args.duration:g}")
    s = EyebotSettings(
        seed=given.seed,
        runs=args.runs,
        period=args.eyebot_period,
        reading=Reading(args.theta_f),
        head_on_right=args.head_on == "right",
        over_walls=args.eyebots_over_walls,
        footbots=tuple(args.footbots),
        ways=tuple(args.ways),
    )
    if save is not None and s.old():  # runs under old readings are kept apart too
        save = save.with_name(f"{save.name}-{'-'.join(s.old())}")
    return replace(
        s,
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
    print(f"readings: {', '.join(s.old()) or 'the new defaults'}")
    if s.save is not None:
        print(f"runs saved in: {s.save}")
    if s.saved_only:
        print("saved runs only (--saved): the tables count the runs each point has")
    everything = []
    for figure in s.figures:
        t0 = time.monotonic()
        pts = s.chosen(points(figure))
        if not pts:
            raise UsageError(f"{figure} has no point with these --footbots and --ways")
        records, made, wall = run_points(s, pts, figure)
        everything.extend(records)
        print(_TABLES[figure](records))
        if figure == "fig2":
            print(_report.fig2_counted(records))
        print(sweep_made(figure, made, t0, wall, _report.speed))
        if not args.no_plots:
            from ._plots import plot

            path = plot(figure, records, args.out, args.format)
            if path is not None:
                print(f"wrote {path}")
    if args.json:
        print(every_run(s.seed, everything))
    return 0
