"""The points of the sweeps, their runs on a pool of worker processes, and the saved runs.

Each point's runs are kept in ``<save>/<point>.jsonl``, one JSON object a line, appended as
they finish; a later run with the same master seed reads them and runs only the missing ones,
so that more trials can be added to a point (``--runs 100`` after ``--runs 50``).
"""

from __future__ import annotations

from dataclasses import replace

from robots.library import WALKS

from .. import _runner
from .._saved import Made, Record
from ._paper import (
    ALPHA_ROBOTS,
    ALPHA_TARGETS,
    CHECK_TARGETS,
    FIG8_ROBOTS,
    FIG9_TARGETS,
    Setup,
)
from ._settings import LevySettings, Point
from ._trial import run_trial

SWEEPS = ("fig8", "fig9", "alpha", "step", "parts", "fig4")
#: The walks of the sweeps beyond the paper's figures (``step`` adds FL at every step).
CHECKS = {
    "step": ("L", "L+P"),
    "parts": ("L", "L+F", "L+S", "L+P"),
    "fig4": ("FL", "FL+S", "L", "L+S", "L+P"),
}


def points(s: LevySettings, sweep: str) -> list[Point]:
    """The points of one sweep: ``fig8`` (targets, 10 robots), ``fig9`` (robots, 8 targets),
    ``alpha`` (the stable index, L and L+P, 10 robots and 8 targets); at 8 targets and each
    of ``s.check_robots``: ``step`` (FL at each of ``s.steps`` beside L and L+P), ``parts``
    (L, L+F, L+S, L+P) and ``fig4`` (FL, FL+S, L, L+S, L+P). A point of FL at the settings'
    own step is the plain FL point (its saved runs are Fig. 9's)."""
    a = s.setup.alpha
    if sweep in CHECKS:
        t = CHECK_TARGETS
        out = []
        for n in s.check_robots:
            out += [Point(m, n, t, a) for m in CHECKS[sweep]]
            if sweep == "step":
                out += [Point("FL", n, t, a, None if f == s.setup.fixed else f) for f in s.steps]
        return out
    if sweep == "fig8":
        return [Point(m, FIG8_ROBOTS, t, a) for t in s.targets for m in s.methods]
    if sweep == "fig9":
        return [Point(m, n, FIG9_TARGETS, a) for n in s.robots for m in s.methods]
    if sweep == "alpha":
        ms = [m for m in s.methods if WALKS[m][0]]  # the walks with Lévy steps
        return [Point(m, ALPHA_ROBOTS, ALPHA_TARGETS, x) for x in s.alphas for m in ms]
    raise ValueError(f"unknown sweep {sweep!r}")


def _setup(s: LevySettings, p: Point) -> Setup:
    setup = replace(s.setup, alpha=p.alpha)
    return setup if p.fixed is None else replace(setup, fixed=p.fixed)


def _one(job: tuple[LevySettings, Point, int]) -> Record:
    s, p, run = job
    rec = run_trial(_setup(s, p), p.method, p.robots, p.targets, s.seed, run)
    rec["seed"] = s.seed
    rec["point"] = p.name
    return rec


def run_points(
    s: LevySettings, pts: list[Point], label: str = ""
) -> tuple[list[Record], Made, float]:
    """Every run of ``pts`` (:func:`experiments._runner.run_points`): all records, a tally of
    the runs made (their robot and wall seconds), and the wall seconds spent making them."""

    def mend(p: Point, runs: dict[int, Record]) -> None:  # runs saved before records named
        fixed = None if WALKS[p.method][0] else _setup(s, p).fixed  # their step
        for r in runs.values():
            r.setdefault("fixed", fixed)

    made = Made(robot_s=lambda r: r["robot_s"], wall_s=lambda r: r["wall_s"])
    records, wall = _runner.run_points(
        s,
        pts,
        _one,
        made,
        label=label,
        status=lambda rec: f"{rec['method']} n={rec['robots']} t={rec['targets']}",
        mend=mend,
    )
    return records, made, wall
