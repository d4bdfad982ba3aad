"""The report of the sweeps beyond the paper's figures: the fixed walk's step against the Lévy
walk (``step``), L+P taken apart (``parts``) and signatures on every walk (``fig4``).

``step`` asks whether L < FL rests on FL's step: the Lévy steps' median (1 m at α = 1, the
default FL step) or their mean (capped at ``Setup.cap``), both measured from the generator
(:func:`step_stats`) and, at α = 1, in closed form (:func:`cauchy_steps`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from robots.library import mantegna

from .._common import summary
from ._paper import Setup
from ._report import Records, paired, table, times

PARTS_PAIRS = (("L+F", "L"), ("L+S", "L"), ("L+P", "L"), ("L+P", "L+F"), ("L+P", "L+S"))
"""The differences ``parts`` prints: each part against L, and what the other part adds."""
FIG4_PAIRS = (("FL+S", "FL"), ("L+S", "L"), ("L", "FL"), ("L+S", "FL+S"), ("L+P", "L+S"))
"""The differences ``fig4`` prints: what signatures give each walk, L against FL without and
with them, and what the field adds to L+S."""
Z = 2.0
"""A paired difference counts as measured when it is this many standard errors from 0."""


def step_stats(setup: Setup, draws: int = 200_000, seed: int = 0) -> tuple[float, float]:
    """The Lévy steps' median and mean (m), measured: ``draws`` steps min(cap, scale · |z|)
    with z from :func:`~robots.library.mantegna` as the walk draws them (n = 100, no
    correction), seeded ``seed``."""
    rng = np.random.default_rng(seed)
    chunk = 10_000
    z = np.concatenate([mantegna(rng, setup.alpha, chunk) for _ in range(-(-draws // chunk))])
    steps = np.minimum(setup.cap, setup.scale * np.abs(z[:draws]))
    return float(np.median(steps)), float(np.mean(steps))


def cauchy_steps(scale: float, cap: float) -> tuple[float, float]:
    """The median and the capped mean of the steps at α = 1 in closed form: eq. 11's a/|b| of
    two standard Gaussians is standard Cauchy, and so is the mean of n of them (eq. 12), so
    |z| has median tan(π/4) = 1 and E min(c, |z|) = ln(1 + c²)/π + c (1 - 2 arctan(c)/π)
    with c = cap / scale."""
    c = cap / scale
    mean = math.log1p(c * c) / math.pi + c * (1.0 - 2.0 * math.atan(c) / math.pi)
    return scale, scale * mean


def step_line(setup: Setup) -> str:
    """The Lévy steps' median and capped mean, measured and (α = 1) in closed form."""
    median, mean = step_stats(setup)
    line = (
        f"Lévy steps (α = {setup.alpha:g}, {setup.scale:g} m a unit, cap {setup.cap:g} m), "
        f"200000 draws of the generator (seed 0): median {median:.3f} m, mean {mean:.3f} m"
    )
    if setup.alpha == 1.0:
        m, c = cauchy_steps(setup.scale, setup.cap)
        line += f"; closed form (|Cauchy| capped): median {m:.3f} m, mean {c:.3f} m"
    return line


def _verdict(d: list[float], a: str, b: str) -> str:
    if len(d) < 2:
        return "-"
    s = summary(d)
    if s.mean + Z * s.se < 0:
        return f"{a} < {b}"
    if s.mean - Z * s.se > 0:
        return f"{a} > {b}"
    return f"{a} ≈ {b}"


Keyed = dict[tuple[Any, ...], float]


def _paired(by: Keyed, a: tuple[Any, ...], b: tuple[Any, ...]) -> list[float]:
    """Paired differences a - b over the runs both have (keys: (*point, run))."""
    runs = sorted({k[-1] for k in by if k[:-1] == a} & {k[-1] for k in by if k[:-1] == b})
    return [by[(*a, k)] - by[(*b, k)] for k in runs]


def step_table(records: Records, setup: Setup) -> str:
    """FL's search time at each of its steps against L and L+P, paired by run, per robot
    count, and for which steps L < FL holds (by ``Z`` standard errors)."""
    by: dict[tuple[Any, ...], float] = {}
    for r, t in zip(records, times(records, setup.max_time), strict=True):
        by[(r["robots"], r["method"], r.get("fixed"), r["run"])] = t
    out = [
        "\nsearch time (s) vs the fixed walk's step, 8 targets (beyond the paper)",
        f"{'robots':>6} {'FL step':>8} {'FL mean ±sd (se)':>24} {'L - FL (se, n)':>24}"
        f" {'L+P - FL (se, n)':>24}   L vs FL ({Z:g} se)",
    ]
    summary_lines = []
    for n in sorted({r["robots"] for r in records}):
        here = [r for r in records if r["robots"] == n]
        for m in ("L", "L+P"):
            mine = [r for r in here if r["method"] == m]
            if mine:
                s = summary(times(mine, setup.max_time))
                out.append(f"{n:>6} {m:>8} {s.mean:7.1f} ±{s.sd:6.1f} ({s.se:5.1f})")
        steps = sorted({r["fixed"] for r in here if r["method"] == "FL"})
        held = []
        for f in steps:
            fl = [r for r in here if r["method"] == "FL" and r["fixed"] == f]
            s = summary(times(fl, setup.max_time))
            cells = []
            for m in ("L", "L+P"):
                d = _paired(by, (n, m, None), (n, "FL", f))
                e = summary(d)
                cells.append(f"{e.mean:+10.1f} ±{e.se:5.1f} (n {e.n:>3})" if d else f"{'-':>22}")
            verdict = _verdict(_paired(by, (n, "L", None), (n, "FL", f)), "L", "FL")
            held.append((f, verdict))
            censored = sum(r["time"] is None for r in fl)
            mark = f" {censored}c" if censored else ""
            out.append(
                f"{n:>6} {f:>7g}m {s.mean:7.1f} ±{s.sd:6.1f} ({s.se:5.1f}){mark:<4}"
                f" {cells[0]:>24} {cells[1]:>24}   {verdict}"
            )
        if held:
            summary_lines.append(f"{n} robots: " + ", ".join(f"{f:g} m {v}" for f, v in held))
    out.append("L vs FL by FL's step (paired, 2 se): " + "; ".join(summary_lines))
    return "\n".join(out)


def interaction(records: Records, setup: Setup) -> str:
    """Whether the two parts of L+P add up: (L+P - L) - (L+F - L) - (L+S - L), paired by run,
    per robot count (0 if the field and the signatures act independently)."""
    by: dict[tuple[Any, ...], float] = {}
    for r, t in zip(records, times(records, setup.max_time), strict=True):
        by[(r["robots"], r["method"], r["run"])] = t
    out = ["\nL+P - L+F - L+S + L, paired by run (0: the two parts add up)"]
    for n in sorted({r["robots"] for r in records}):
        runs = [k for (nn, m, k) in by if nn == n and m == "L"]
        d = [
            by[(n, "L+P", k)] - by[(n, "L+F", k)] - by[(n, "L+S", k)] + by[(n, "L", k)]
            for k in runs
            if all((n, m, k) in by for m in ("L+P", "L+F", "L+S"))
        ]
        s = summary(d)
        out.append(f"{n:>7} robots {s.mean:+10.1f} ±{s.se:5.1f} (n {s.n:>3})" if d else f"{n:>7} -")
    return "\n".join(out)


def checks_report(sweep: str, records: Records, setup: Setup, methods: tuple[str, ...]) -> str:
    """The tables of a ``step``, ``parts`` or ``fig4`` sweep."""
    if sweep == "step":
        return step_line(setup) + "\n" + step_table(records, setup)
    title = {
        "parts": "L+P taken apart: field only (L+F), signatures only (L+S), both (L+P); 8 targets",
        "fig4": "signatures on every walk (Fig. 4's controller): FL+S, L+S, L+P; 8 targets",
    }[sweep]
    pairs = PARTS_PAIRS if sweep == "parts" else FIG4_PAIRS
    out = [
        table(records, "robots", f"search time (s) vs robots, {title}", setup, methods),
        paired(records, "robots", setup, pairs),
    ]
    if sweep == "parts":
        out.append(interaction(records, setup))
    return "\n".join(out)
