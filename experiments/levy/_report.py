"""The Lévy experiment's report: search time mean ± sd (se) per point, the paper's ordering
beside the measured one, the saturation with more robots, and the α sweep against theory."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from typing import Any

from robots.library import stable_alpha, viswanathan_mu

from .. import _runner
from .._common import summary
from .._saved import Made
from ._paper import ORDER, Setup

Records = list[dict[str, Any]]


def times(records: Records, cap: float) -> list[float]:
    """Search times, a censored run counted as ``cap`` (so a mean with censored runs is a
    lower bound)."""
    return [cap if r["time"] is None else float(r["time"]) for r in records]


def _by(records: Records, key: str) -> dict[tuple[Any, str], Records]:
    groups: dict[tuple[Any, str], Records] = defaultdict(list)
    for r in records:
        groups[(r[key], r["method"])].append(r)
    return groups


def _cell(recs: Records, cap: float) -> str:
    if not recs:
        return f"{'-':>24}"
    s = summary(times(recs, cap))
    censored = sum(r["time"] is None for r in recs)
    mark = f"{censored}c" if censored else ""
    return f"{s.mean:7.1f} ±{s.sd:6.1f} ({s.se:5.1f}){mark:>3}"


def table(
    records: Records,
    key: str,
    title: str,
    setup: Setup,
    methods: Sequence[str] | None = None,
) -> str:
    """Mean ± sd (se) of the search time (s) against ``key`` (``targets``, ``robots`` or
    ``alpha``), one column per method, and whether the paper's ordering holds at each row
    (``methods``: these columns instead of the paper's three, and no ordering)."""
    groups = _by(records, key)
    ours = methods is not None
    methods = [m for m in (methods or ORDER) if any(r["method"] == m for r in records)]
    xs = sorted({r[key] for r in records})
    out = [f"\n{title}", f"{key:>7} " + "".join(f"{m + ' mean ±sd (se)':>25}" for m in methods)]
    if key != "alpha" and not ours:
        out[-1] += "   measured order   paper"
    for x in xs:
        row = f"{x:>7g} " + "".join(f" {_cell(groups[(x, m)], setup.max_time)}" for m in methods)
        if key != "alpha" and not ours:
            means = {m: summary(times(groups[(x, m)], setup.max_time)).mean for m in methods}
            order = " < ".join(sorted(means, key=lambda m: means[m]))
            row += f"   {order:<16} {' < '.join(ORDER)}"
        out.append(row)
    runs = sorted({len(v) for v in groups.values()})
    censored = sum(r["time"] is None for r in records)
    out.append(
        f"(runs per point: {runs}; censored at {setup.max_time:g} s: {censored}, marked 'c'"
        " and counted as that time)"
    )
    return "\n".join(out)


def saturation(records: Records, setup: Setup) -> str:
    """Fig. 9's saturation: the speed-up n0 T(n0)/T(n) against the ideal n (n0 the fewest
    robots run, normally 1), and the efficiency n0 T(n0)/(n T(n)) per method."""
    groups = _by(records, "robots")
    ns = sorted({r["robots"] for r in records})
    methods = [m for m in ORDER if any(r["method"] == m for r in records)]
    n0 = min(ns)
    out = [
        f"\nsaturation (Fig. 9): speed-up {n0} T({n0})/T(n) and efficiency"
        f" {n0} T({n0})/(n T(n)) (1 if robots added independent work)"
    ]
    out.append(f"{'robots':>7} " + "".join(f"{m + ' speed-up, eff.':>24}" for m in methods))
    for n in ns:
        cells = []
        for m in methods:
            base = groups.get((min(ns), m))
            here = groups.get((n, m))
            if not base or not here:
                cells.append(f"{'-':>24}")
                continue
            t1 = summary(times(base, setup.max_time)).mean * min(ns)
            tn = summary(times(here, setup.max_time)).mean
            cells.append(f"{t1 / tn:14.2f} {t1 / (n * tn):9.2f}")
        out.append(f"{n:>7} " + "".join(cells))
    return "\n".join(out)


def estimate(setup: Setup, targets: int) -> tuple[float, float]:
    """λ, the mean free path between targets (1/(2 r_v ρ), ρ their density), and
    Viswanathan's μ for it (eq. 4-5)."""
    lam = 1.0 / (2.0 * setup.walk.sense_range * targets / setup.size**2)
    return lam, viswanathan_mu(lam, setup.walk.sense_range)


def theory(setup: Setup, targets: int) -> str:
    """What the theory predicts for the α sweep: Viswanathan's estimate (eq. 4-5) for
    non-destructive search, and that destructive search's optimum is ballistic."""
    lam, mu = estimate(setup, targets)
    return (
        f"theory: λ = 1/(2 r_v ρ) = {lam:.1f} m for {targets} targets (r_v = "
        f"{setup.walk.sense_range:g} m); non-destructive optimum (eq. 4-5) μ = {mu:.2f}, "
        f"stable α = {stable_alpha(mu):.2f}; destructive search (a found target does not count "
        "again, as here): the optimum moves to μ → 1, α → 0, ballistic motion (Viswanathan et "
        "al. 1999; Santos et al. 2004)"
    )


def speed(made: Made, wall: float) -> str:
    """Simulated robot-seconds per wall second of the runs just made (``made``: their sums of
    ``robot_s`` and ``wall_s``)."""
    return _runner.speed(made.sums["robot_s"], made.sums["wall_s"], wall, "robot-seconds")


def paired(
    records: Records,
    key: str,
    setup: Setup,
    pairs: Sequence[tuple[str, str]] = (("L+P", "L"), ("L", "FL")),
) -> str:
    """The methods' differences paired by run (the same arena, targets and starts): mean ±
    se of each of ``pairs`` (a - b; L+P - L and L - FL unless told) at each ``key``, and how
    many runs each pair shares."""
    by: dict[tuple[Any, str, int], float] = {}
    for r, t in zip(records, times(records, setup.max_time), strict=True):
        by[(r[key], r["method"], r["run"])] = t
    xs = sorted({r[key] for r in records})
    pairs = [(a, b) for a, b in pairs if any(k[1] == a for k in by)]
    pairs = [(a, b) for a, b in pairs if any(k[1] == b for k in by)]
    if not pairs:
        return ""
    out = [f"\npaired by run (same arena and starts): mean ± se of the difference (s) by {key}"]
    out.append(f"{key:>7} " + "".join(f"{a + ' - ' + b:>22}" for a, b in pairs))
    for x in xs:
        cells = []
        for a, b in pairs:
            runs = [k for (xx, m, k) in by if xx == x and m == a and (x, b, k) in by]
            d = [by[(x, a, k)] - by[(x, b, k)] for k in runs]
            s = summary(d)
            cells.append(f"{s.mean:+10.1f} ±{s.se:5.1f} (n {s.n:>3})" if d else f"{'-':>22}")
        out.append(f"{x:>7g} " + "".join(cells))
    return "\n".join(out)
