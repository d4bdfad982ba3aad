"""The eye-bot experiment's tables, beside what the paper's figures show, and its claims checked.

Every time is in simulated seconds; mean ± sd over the runs (the paper's error bars are one
standard deviation), n the number of runs that have the figure (a run in which no foot-bot
reached the target has no t_1: it is counted apart as "never").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .. import _runner
from .._common import plus_minus, summary
from .._saved import Made
from ._sweep import DEPLOY_EVERY, FIG3_FOOTBOTS, arena

Records = Sequence[dict[str, Any]]
BINS = 5
"""ρ histograms: five intervals of 0.2, as in the paper's Fig. 3 and 4."""


def _of(records: Records, **match: Any) -> list[dict[str, Any]]:
    return [r for r in records if all(r.get(k) == v for k, v in match.items())]


def _cell(values: Sequence[float | None]) -> str:
    got = [float(v) for v in values if v is not None]
    if not got:
        return f"{'-':>17}"
    s = summary(got)
    sd = 0.0 if math.isnan(s.sd) else s.sd
    return f"{plus_minus(s.mean, sd, '6.0f', '5.0f')} ({s.n:>3})"


def fig2(records: Records) -> str:
    """t_1, t_a (eye-bots learning) and t_s (pre-programmed) against the foot-bots."""
    speed = 0.3
    best = arena("cluttered").optimum / speed
    out = [
        "\nFig. 2, cluttered arena: travel times (s), mean ± sd (runs)",
        f"{'foot-bots':>9} {'t_1':>17} {'t_a':>17} {'t_s':>17} {'never':>6}  t_a < t_1  t_a/t_s"
        f" {'median trip':>17}",
    ]
    for n in sorted({r["footbots"] for r in _of(records, arena="eyebot-cluttered")}):
        learn = _of(records, arena="eyebot-cluttered", footbots=n, eyebots="learning")
        short = _of(records, arena="eyebot-cluttered", footbots=n, eyebots="shortest")
        t1 = [r["t_1"] for r in learn]
        ta = [r["t_a"] for r in learn]
        ts = [r["t_a_all"] for r in short]
        never = sum(v is None for v in t1)
        m1, ma, ms = (_mean(v) for v in (t1, ta, ts))
        below = "yes" if ma < m1 else ("no" if not math.isnan(ma + m1) else "-")
        ratio = f"{ma / ms:7.2f}" if ms and not math.isnan(ma / ms) else f"{'-':>7}"
        median = _cell([r.get("t_a_median") for r in learn])  # runs saved before had none
        out.append(
            f"{n:>9} {_cell(t1)} {_cell(ta)} {_cell(ts)} {never:>6}  {below:>9}  {ratio} {median}"
        )
    out.append(
        f"(the shortest way through our eye-bots: {best:.0f} s at {speed} m/s between the eye-bots"
        " under the areas; the paper: t_s = 76 s for one foot-bot against a 73 s optimum for its"
        " placement, t_a close to t_s and far below t_1, t_1 falling with more foot-bots; median"
        " trip: the median of a run's trips after each foot-bot's first, its mean over the runs)"
    )
    return "\n".join(out)


def fig2_counted(records: Records) -> str:
    """Fig. 2's t_a two ways, every run counted, against the must-show bounds.

    ``t_a``: every trip after a foot-bot's first, over the whole run (learning included);
    ``late``: only those begun in the run's second half. A run with no such trip is not left
    out: it counts as the span it had for one (the run's length for ``t_a``, half of it for
    ``late``: a trip that never ended took at least about that), and how many did so is shown
    (``none``). t_1 likewise counts a run that never reached the target as the run's length.
    Every ratio is of means over the runs; t_s is the mean trip with pre-programmed eye-bots.
    """
    out = [
        "\nFig. 2, every run counted (a run with no trip to count is counted as the span it"
        " had: t_a the run's length, late half of it, t_1 the run's length), means over the runs",
        f"{'foot-bots':>9} {'runs':>4} {'t_1':>6} {'t_a':>6} {'none':>4} {'late':>6} {'none':>4}"
        f" {'median':>6} {'t_s':>5} {'t_a/t_s':>7} {'late/t_s':>8} {'med/t_s':>7}"
        "  t_a<=2t_s  med<=1.5t_s  t_a<t_1",
    ]
    for n in sorted({r["footbots"] for r in _of(records, arena="eyebot-cluttered")}):
        learn = _of(records, arena="eyebot-cluttered", footbots=n, eyebots="learning")
        short = _of(records, arena="eyebot-cluttered", footbots=n, eyebots="shortest")
        if not learn:
            continue
        length = [float(r["duration"]) for r in learn]
        t1 = _counted([r["t_1"] for r in learn], length)
        ta = _counted([r["t_a"] for r in learn], length)
        late = _counted([r.get("t_a_late") for r in learn], [d / 2 for d in length])
        med = _counted([r.get("t_a_median") for r in learn], length)
        ts = _mean([r["t_a_all"] for r in short])
        none = sum(r["t_a"] is None for r in learn)
        none_late = sum(r.get("t_a_late") is None for r in learn)
        out.append(
            f"{n:>9} {len(learn):>4} {t1:6.0f} {ta:6.0f} {none:>4} {late:6.0f} {none_late:>4}"
            f" {med:6.0f} {ts:5.0f} {ta / ts:7.2f} {late / ts:8.2f} {med / ts:7.2f}"
            f"  {_yes(ta, 2 * ts):>9}  {_yes(med, 1.5 * ts):>11}  {_yes(ta, t1, strict=True):>7}"
        )
    out.append(
        "(median: the median of a run's later trips, its mean over the runs; late: later trips"
        " begun in the run's second half; a ratio with no t_s runs is nan)"
    )
    return "\n".join(out)


def _counted(values: Sequence[float | None], instead: Sequence[float]) -> float:
    """The mean of ``values``, a missing one counted as its ``instead``."""
    got = [float(v) if v is not None else alt for v, alt in zip(values, instead, strict=True)]
    return float(np.mean(got)) if got else math.nan


def _yes(value: float, bound: float, strict: bool = False) -> str:
    """Whether ``value`` is within ``bound`` (below it, if ``strict``); "-" if either is nan."""
    if math.isnan(value) or math.isnan(bound):
        return "-"
    return "yes" if (value < bound if strict else value <= bound) else "no"


def histogram(values: Sequence[float]) -> list[float]:
    """Fractions of ``values`` (ρ) in the five intervals [0, 0.2), …, [0.8, 1]."""
    if not values:
        return [math.nan] * BINS
    counts = np.histogram(values, bins=BINS, range=(0.0, 1.0))[0]
    return [float(c) / len(values) for c in counts]


def _hist_row(label: str, rhos: Sequence[float]) -> str:
    cells = "".join(f"{f:7.2f}" for f in histogram(rhos))
    return f"{label:>12} {cells}   {len(rhos):>4}"


def _header() -> str:
    return f"{'':>12} " + "".join(f"{f'<{(i + 1) / BINS:.1f}':>7}" for i in range(BINS)) + "   runs"


def fig3_panels(records: Records) -> list[tuple[str, list[float]]]:
    """Fig. 3's ρ of each run, by corridor ratio (``r1``, ``r1.5``, ``r2``)."""
    names = sorted({r["arena"] for r in records if r["arena"].startswith("double")})
    panels = []
    for name in names:
        rows = _of(records, arena=name, footbots=FIG3_FOOTBOTS, eyebots="learning")
        rhos = [r["rho"] for r in rows if r["rho"] is not None]
        if rhos:
            panels.append((name.removeprefix("double-corridor-"), rhos))
    return panels


def fig4_panels(records: Records) -> list[tuple[int, list[float]]]:
    """Fig. 4's ρ of each run, by the number of foot-bots (equal corridors)."""
    rows = _of(records, arena="double-corridor-r1", eyebots="learning")
    panels = []
    for n in sorted({r["footbots"] for r in rows}):
        rhos = [r["rho"] for r in rows if r["footbots"] == n and r["rho"] is not None]
        if rhos:
            panels.append((n, rhos))
    return panels


def fig3(records: Records) -> str:
    """ρ histograms for r = 1, 1.5, 2 (15 foot-bots deployed one every 30 s)."""
    windows = sorted({float(r.get("window", 1000.0)) for r in records if "rho" in r} or {1000.0})
    over = " or ".join(f"{w:g}" for w in windows)  # runs saved before it was kept: 1000 s
    out = [
        f"\nFig. 3, double corridor, {FIG3_FOOTBOTS} foot-bots, one every {DEPLOY_EVERY:g} s:"
        f" fraction of runs by ρ = c_r / (c_r + c_l) over the last {over} s (c_r: the shorter"
        " corridor, the right one; the left one in a mirrored arena)",
        _header(),
    ]
    shorter = []
    for name, rhos in fig3_panels(records):
        out.append(_hist_row(name, rhos))
        shorter.append((name, sum(p >= 0.8 for p in rhos) / len(rhos)))
    out.append(
        "converged on the shorter (right) corridor, ρ ≥ 0.8: "
        + ", ".join(f"{n} {f:.2f}" for n, f in shorter)
        + " (the paper: either corridor for r = 1, more often the shorter as r grows)"
    )
    return "\n".join(out)


def fig4(records: Records) -> str:
    """ρ histograms for 1 to 30 foot-bots, equal corridors."""
    out = [
        "\nFig. 4, equal corridors: fraction of runs by ρ against the number of foot-bots",
        _header(),
    ]
    for n, rhos in fig4_panels(records):
        middle = sum(0.2 <= p < 0.8 for p in rhos) / len(rhos)
        out.append(_hist_row(f"{n} foot-bots", rhos) + f"   spread {middle:.2f}")
    out.append(
        "(spread: the fraction with 0.2 ≤ ρ < 0.8; the paper: ρ 0 or 1 for few foot-bots,"
        " from bimodal over uniform to unimodal as they grow)"
    )
    return "\n".join(out)


def fig5(records: Records) -> str:
    """t_a against ρ: spread traffic (0.2 ≤ ρ < 0.8) against traffic on one corridor."""
    out = [
        "\nFig. 5, equal corridors: t_a (s) when traffic is spread and when it is on one corridor",
        f"{'foot-bots':>9} {'spread':>17} {'one corridor':>17}   corr(t_a, |ρ - 0.5|)",
    ]
    rows = _of(records, arena="double-corridor-r1", eyebots="learning")
    for n in sorted({r["footbots"] for r in rows if r["footbots"] >= 10}):
        mine = [r for r in rows if r["footbots"] == n and r["rho"] is not None and r["t_a"]]
        spread = [r["t_a"] for r in mine if 0.2 <= r["rho"] < 0.8]
        focused = [r["t_a"] for r in mine if not 0.2 <= r["rho"] < 0.8]
        corr = math.nan
        if len(mine) > 2:
            x = np.array([abs(r["rho"] - 0.5) for r in mine])
            y = np.array([r["t_a"] for r in mine])
            if x.std() > 0 and y.std() > 0:
                corr = float(np.corrcoef(x, y)[0, 1])
        out.append(f"{n:>9} {_cell(spread)} {_cell(focused)}   {corr:8.2f}")
    out.append("(the paper: t_a lower when traffic is spread, more so with more foot-bots)")
    return "\n".join(out)


def beyond(records: Records) -> str:
    """Trip-time weights (the paper's future work) against plain learning, paired by run."""
    out = [
        "\nBeyond the paper: eye-bots weigh what they learn by the trip time foot-bots report;"
        " corridors r = 1.5, t_a (s)",
        f"{'foot-bots':>9} {'learning':>17} {'weighted':>17}   weighted - learning (paired, ± se)",
    ]
    rows = _of(records, arena="double-corridor-r1.5")
    for n in sorted({r["footbots"] for r in rows}):
        plain = {
            r["run"]: r["t_a"] for r in rows if r["footbots"] == n and r["eyebots"] == "learning"
        }
        weigh = {r["run"]: r["t_a"] for r in rows if r["footbots"] == n and r["eyebots"] == "weigh"}
        both = [k for k in plain if k in weigh and plain[k] is not None and weigh[k] is not None]
        diff = summary([weigh[k] - plain[k] for k in both])
        paired = f"{diff.mean:+7.1f} ± {diff.se:5.1f} ({diff.n})" if both else "-"
        out.append(f"{n:>9} {_cell(list(plain.values()))} {_cell(list(weigh.values()))}   {paired}")
    return "\n".join(out)


def _by_run(rows: Records, footbots: int, eyebots: str) -> dict[int, float | None]:
    return {
        r["run"]: r["t_a"] for r in rows if r["footbots"] == footbots and r["eyebots"] == eyebots
    }


def speed(made: Made, wall: float) -> str:
    """Simulated foot-bot-seconds per wall second of the runs just made (``made``: their sums
    of ``sim_s``, foot-bots times duration, and ``wall_s``)."""
    return _runner.speed(made.sums["sim_s"], made.sums["wall_s"], wall, "foot-bot-seconds")


def _mean(values: Sequence[float | None]) -> float:
    got = [float(v) for v in values if v is not None]
    return float(np.mean(got)) if got else math.nan
