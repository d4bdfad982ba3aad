"""The points of the sweeps, their runs on a pool of worker processes, and the saved runs.

Each point's runs are kept in ``<save>/<point>.jsonl``, one JSON object a line, appended as
they finish; a later run with the same master seed reads them and runs only the missing ones,
so that more trials can be added to a point (``--runs 100`` after ``--runs 50``).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

from robots.library import WALKS

from .._common import Progress
from .._saved import Made, Record, load_runs, run_pool
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


def load(save: Path | None, point: Point, seed: int) -> dict[int, Record]:
    """The saved runs of ``point`` under master ``seed``, by run index."""
    return load_runs(None if save is None else save / f"{point.name}.jsonl", seed)


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
    """Every run of ``pts`` (saved ones read back, missing ones run on ``s.workers``
    processes, saved as they finish and read back with the rest; kept as made when nothing is
    saved): all records, a tally of the runs made (their robot and wall seconds), and the wall
    seconds spent making them."""
    before = {p: set(load(s.save, p, s.seed)) for p in pts}
    jobs = [(s, p, k) for p in pts for k in range(s.runs) if k not in before[p]]
    t0 = time.monotonic()
    save = s.save

    def save_to(rec: Record) -> Path:
        assert save is not None
        return save / f"{rec['point']}.jsonl"

    made = Made(robot_s=lambda r: r["robot_s"], wall_s=lambda r: r["wall_s"])
    kept: list[Record] = []  # the runs made, when no file keeps them

    def each(rec: Record) -> None:
        made(rec)
        if save is None:
            kept.append(rec)

    run_pool(
        jobs,
        _one,
        workers=s.workers,
        save_to=None if save is None else save_to,
        bar=Progress(len(jobs), label, enabled=s.progress and bool(jobs)),
        status=lambda rec: f"{rec['method']} n={rec['robots']} t={rec['targets']}",
        on=s.executor,
        describe=lambda job: f"{job[1].name} run {job[2]} (--seed {job[0].seed})",
        each=each,
    )
    wall = time.monotonic() - t0
    have = {p: load(s.save, p, s.seed) for p in pts}
    for p in pts:  # runs saved before records named their step
        fixed = None if WALKS[p.method][0] else _setup(s, p).fixed
        for r in have[p].values():
            r.setdefault("fixed", fixed)
    made_here = {(p, k) for _, p, k in jobs}
    records = [r for p in pts for k, r in sorted(have[p].items()) if (p, k) not in made_here]
    records += [have[p][k] for _, p, k in jobs] if save is not None else kept
    return [r for r in records if r["run"] < s.runs], made, wall
