"""`mover experiment levy`: its command line, the settings it makes of it, and the run."""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

from mover.cli import UsageError
from robots.library import METHODS, WALKS, LevyParams

from .._common import (
    add_list_arguments,
    add_run_arguments,
    comma_list,
    read_run_arguments,
    runner_parser,
    shown,
)
from .._runner import add_runner_tail, every_run, save_dir, sweep_made
from ._checks import checks_report
from ._paper import (
    ALPHA_TARGETS,
    ALPHAS,
    CHECK_ROBOTS,
    FIG8_TARGETS,
    FIG9_ROBOTS,
    ORDER,
    STEPS,
    Setup,
)
from ._report import paired, saturation, speed, table, theory
from ._settings import LevySettings
from ._sweep import CHECKS, SWEEPS, points, run_points

MAX_TIME = 1e6
"""The longest censoring time a run may be given (simulated s)."""
# The options that set the fields of the same names in LevyParams and in Setup.
_WALK_OPTIONS = ("rho0", "k_rep", "signature_range", "k_sig", "own_signatures")
_SETUP_OPTIONS = ("alpha", "max_time", "scale", "cap", "fixed")
_KEYS = {"fig8": "targets", "fig9": "robots", "alpha": "alpha"}
_TITLES = {
    "fig8": "search time (s) vs number of targets, 10 robots (Fig. 8)",
    "fig9": "search time (s) vs number of robots, 8 targets (Fig. 9)",
    "alpha": "search time (s) vs stable index α, 10 robots, 8 targets (beyond the paper)",
}


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``levy`` experiment runner."""
    from . import __doc__ as doc

    help = "FL, Lévy and Lévy + potential field search on seeded arenas (Sutantyo et al., V)"
    parser = runner_parser(sub, "levy", help, doc)
    parser.add_argument(
        "--sweep",
        type=comma_list(str, SWEEPS),
        default=["fig8", "fig9"],
        help="comma list of fig8, fig9, alpha, and beyond the paper at 8 targets and"
        " --check-robots: step (FL at each of --steps against L and L+P), parts (L, L+F: field"
        " only, L+S: signatures only, L+P) and fig4 (signatures on every walk: FL, FL+S, L,"
        " L+S, L+P) (default fig8,fig9)",
    )
    add_run_arguments(parser, runs=50, seed=None, workers=2)
    add_list_arguments(
        parser,
        (
            "--methods",
            comma_list(str, tuple(WALKS)),
            METHODS,
            "fig8, fig9, alpha: comma list of FL, L, L+P, or the parts L+F, L+S, FL+S"
            " (default FL,L,L+P)",
        ),
        (
            "--targets",
            comma_list(int),
            FIG8_TARGETS,
            f"Fig. 8's target counts {shown(FIG8_TARGETS)}",
        ),
        ("--robots", comma_list(int), FIG9_ROBOTS, f"Fig. 9's robot counts {shown(FIG9_ROBOTS)}"),
        (
            "--alphas",
            comma_list(float),
            ALPHAS,
            f"stable indices of the alpha sweep {shown(ALPHAS)}",
        ),
        ("--steps", comma_list(float), STEPS, f"the step sweep's FL steps (m) {shown(STEPS)}"),
        (
            "--check-robots",
            comma_list(int),
            CHECK_ROBOTS,
            f"robot counts of the step, parts and fig4 sweeps {shown(CHECK_ROBOTS)}",
        ),
    )
    parser.add_argument("--alpha", type=float, default=Setup.alpha, help="the walks' α (1)")
    parser.add_argument("--max-time", type=float, default=Setup.max_time, help="censor (s)")
    walk = LevyParams()
    for flag, default, what in (
        ("--scale", Setup.scale, "metres per unit Lévy step"),
        ("--cap", Setup.cap, "the longest Lévy step (m)"),
        ("--fixed", Setup.fixed, "the fixed-length walk's step (m)"),
        ("--rho0", walk.rho0, "ρ0 of eq. 9: robots repel within it (m)"),
        ("--k-rep", walk.k_rep, "k_rep of eq. 9 among robots"),
        ("--signature-range", walk.signature_range, "a found target's signature reach (m)"),
        ("--k-sig", walk.k_sig, "k_rep of a signature"),
    ):
        parser.add_argument(flag, type=float, default=default, help=f"{what} ({default:g})")
    parser.add_argument(
        "--own-signatures",
        action="store_true",
        help="L+P: a robot is repelled by the targets it marked itself too (the paper: others)",
    )
    add_runner_tail(parser, "levy", run)


def settings(args: argparse.Namespace) -> LevySettings:
    """The settings the command line asks for, checked. Raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    given = read_run_arguments(args)
    counts = (*args.targets, *args.robots, *args.check_robots)
    if min(counts) < 1:
        raise UsageError("--targets, --robots and --check-robots must be positive")
    if max(counts) > 1000:
        raise UsageError("--targets, --robots and --check-robots must be at most 1000")
    if not all(math.isfinite(f) and 0 < f <= 1000 for f in args.steps):
        raise UsageError("--steps must be positive, at most 1000 m")
    if not all(0 < a <= 2 for a in [*args.alphas, args.alpha]):
        raise UsageError("--alpha and --alphas must be in (0, 2]")
    numbers = (args.max_time, args.scale, args.fixed, args.rho0, args.signature_range)
    gains = (args.k_rep, args.k_sig)
    if (
        not all(math.isfinite(x) and x > 0 for x in numbers)
        or not all(math.isfinite(k) and k >= 0 for k in gains)
        or not (args.cap > 0 and not math.isnan(args.cap))
        or args.max_time > MAX_TIME
    ):
        raise UsageError(
            f"--max-time (at most {MAX_TIME:g} s), --scale, --fixed, --rho0 and"
            " --signature-range must be positive and finite, --cap positive (inf: no cap),"
            " --k-rep and --k-sig finite and not negative"
        )
    walk = replace(LevyParams(), **{name: getattr(args, name) for name in _WALK_OPTIONS})
    setup = replace(Setup(), walk=walk, **{name: getattr(args, name) for name in _SETUP_OPTIONS})
    save = save_dir(args)
    if save is not None and setup.tag():  # runs of other settings are kept apart
        save = save.with_name(f"{save.name}-{setup.tag()}")
    return LevySettings(
        seed=given.seed,
        runs=args.runs,
        sweeps=tuple(args.sweep),
        methods=tuple(args.methods),
        targets=tuple(args.targets),
        robots=tuple(args.robots),
        alphas=tuple(args.alphas),
        steps=tuple(args.steps),
        check_robots=tuple(args.check_robots),
        workers=given.workers,
        executor=args.executor,
        setup=setup,
        save=save,
        out=None if args.no_plots else args.out,
        format=args.format,
        json=args.json,
        progress=not args.quiet,
    )


def run(args: argparse.Namespace) -> int:
    """Run the sweeps; print the seed, a table per sweep, the saturation and the speed."""
    s = settings(args)
    print(f"seed: {s.seed}")
    print(f"sweeps: {','.join(s.sweeps)}  methods: {','.join(s.methods)}  runs: {s.runs}")
    print(f"setup: {s.setup}")
    if s.save is not None:
        print(f"runs saved in: {s.save}")
    everything = []
    for sweep in s.sweeps:
        t0 = time.monotonic()
        records, made, wall = run_points(s, points(s, sweep), sweep)
        everything.extend(records)
        if sweep in CHECKS:
            print(checks_report(sweep, records, s.setup, CHECKS[sweep]))
        else:
            cols = None if set(s.methods) <= set(ORDER) else s.methods
            print(table(records, _KEYS[sweep], _TITLES[sweep], s.setup, cols))
            print(paired(records, _KEYS[sweep], s.setup))
        if sweep == "fig9":
            print(saturation(records, s.setup))
        if sweep == "alpha":
            print(theory(s.setup, ALPHA_TARGETS))
        print(sweep_made(sweep, made, t0, wall, speed))
        if s.out is not None and sweep not in CHECKS:  # tables only beyond the figures
            from ._plots import plot

            print(f"wrote {plot(sweep, records, s.setup, s.out, s.format)}")
    if s.json:
        print(every_run(s.seed, everything))
    return 0
