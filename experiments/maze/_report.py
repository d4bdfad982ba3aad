"""The maze experiment's report: mean ± sd tables and the composite index (section V-B)."""

from __future__ import annotations

import math
from collections import defaultdict
from typing import Any

import numpy as np

from .._common import plus_minus, summary
from .._figures import shared_precision
from ._paper import EXTRA, METRICS

Records = list[dict[str, Any]]
#: Composite index: obstacle probability (None: a given maze) -> method -> agents -> points.
Scores = dict[Any, dict[str, dict[int, float]]]


def group(records: Records) -> dict[tuple[Any, str, int], Records]:
    """The records by (obstacle probability, method, agent count)."""
    groups: dict[tuple[Any, str, int], Records] = defaultdict(list)
    for r in records:
        groups[(r["p"], r["method"], r["agents"])].append(r)
    return groups


def probabilities(records: Records) -> list[Any]:
    """The obstacle probabilities of ``records``, highest first (a given maze before them)."""
    return sorted({r["p"] for r in records}, key=lambda v: -1 if v is None else -v)


def where(p: float | None) -> str:
    """What a table is of: a given maze or an obstacle probability."""
    return "given maze" if p is None else f"obstacle probability {p:g}"


def tables(records: Records, methods: list[str], agents: list[int]) -> str:
    """Mean ± sd (over the runs, ddof 0) of every metric: one table per obstacle probability
    and metric, one precision a table (``shared_precision``)."""
    groups = group(records)
    out = []
    for p in probabilities(records):
        for key, label, _ in (*METRICS, *((k, lbl, False) for k, lbl in EXTRA)):
            out.append(f"\n{label} — {where(p)} (mean ± sd over the runs)")
            out.append(f"{'method':<8} " + " ".join(f"{'n=' + str(n):>17}" for n in agents))
            cells = {
                (m, n): [r[key] for r in groups.get((p, m, n), [])] for m in methods for n in agents
            }
            digits = shared_precision([summary(v, ddof=0).mean for v in cells.values() if v])
            for m in methods:
                row = [f"{_fmt(cells[m, n], digits):>17}" for n in agents]
                out.append(f"{m:<8} " + " ".join(row))
        runs = {len(v) for (pp, _, _), v in groups.items() if pp == p}
        incomplete = sum(not r["complete"] for r in records if r["p"] == p)
        out.append(f"(runs per cell: {sorted(runs)}; incomplete runs: {incomplete})")
    return "\n".join(out)


def _fmt(vals: list[float], digits: int) -> str:
    if not vals:
        return "-"
    s = summary(vals, ddof=0)
    return plus_minus(s.mean, s.sd, f".{digits}f")


def composite(records: Records, methods: list[str], agents: list[int]) -> Scores:
    """Section V-B: per agent count, min-max normalise each metric's means over the methods,
    rank the methods (best gets the most points, ties share), and sum the ranks (weights 1)."""
    groups = group(records)
    scores: Scores = {}
    for p in {r["p"] for r in records}:
        per: dict[str, dict[int, float]] = {m: {} for m in methods}
        for n in agents:
            present = [m for m in methods if groups.get((p, m, n))]
            for m in present:
                per[m][n] = 0.0
            for key, _, higher in METRICS:
                means = np.array([np.mean([r[key] for r in groups[(p, m, n)]]) for m in present])
                lo, hi = means.min(), means.max()
                norm = (means - lo) / (hi - lo) if hi > lo else np.zeros_like(means)
                goodness = norm if higher else -norm
                for m, g in zip(present, goodness, strict=True):
                    # rank points: 1 + number beaten + half the ties
                    per[m][n] += 1 + np.sum(goodness < g) + 0.5 * (np.sum(goodness == g) - 1)
        scores[p] = per
    return scores


def composite_text(scores: Scores, agents: list[int]) -> str:
    """The composite-index table and ranking per obstacle probability."""
    out = []
    for p, per in sorted(scores.items(), key=lambda kv: -1 if kv[0] is None else -kv[0]):
        out.append(f"\ncomposite index (section V-B, higher is better) — {where(p)}")
        out.append(
            f"{'method':<8} " + " ".join(f"{'n=' + str(n):>6}" for n in agents) + f" {'total':>7}"
        )
        totals = {m: sum(v.values()) for m, v in per.items()}
        for m in sorted(per, key=lambda m: -totals[m]):
            out.append(
                f"{m:<8} "
                + " ".join(f"{per[m].get(n, math.nan):6.1f}" for n in agents)
                + f" {totals[m]:7.1f}"
            )
        out.append("ranking: " + " > ".join(sorted(per, key=lambda m: -totals[m])))
    return "\n".join(out)
