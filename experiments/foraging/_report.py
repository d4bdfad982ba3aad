"""The foraging experiment's report: Tables 1-3 and Figure 9, ours beside the paper's.

Each function takes the measured rows and returns the table as text and its figures for the
JSON summary (means rounded to 0.1; NaN where a row has no finished run).
"""

from __future__ import annotations

import math
from typing import Any

from .._common import plus_minus
from ._paper import PAPER_FIG9_GAPS, PAPER_T1, PAPER_T2, PAPER_T3
from ._trial import Row

Figures = dict[str, Any]


def cell(row: Row) -> str:
    """A row's mean ± sample standard deviation, or n/a without a finished run."""
    st = row.stats
    return plus_minus(st.mean, st.sd, "9.1f", "7.1f") if st.n else "      n/a         "


def runs(row: Row) -> str:
    """How many runs a row holds, its relative standard error, and its unfinished runs."""
    miss = f" +{row.unfinished} unfinished" if row.unfinished else ""
    count = f"{row.n:5d} runs" if row.draws == 1 else f"{row.envs:5d} envs x {row.draws} seeds"
    return f"{count}, se {100 * row.rel_se:4.1f}%{miss}"


def _means(keys: list[int], rows: list[Row]) -> dict[str, float]:
    return {str(k): round(r.mean, 1) for k, r in zip(keys, rows, strict=True)}


def _draws(name: str, keys: list[int], rows: list[Row]) -> Figures:
    """With several agent seeds per environment: each row's standard error (over environments)
    and the mean of each agent seed alone, so that one can see how far one draw goes."""
    if not rows or rows[0].draws == 1:
        return {}
    se = {str(k): round(r.rel_se * r.mean, 1) for k, r in zip(keys, rows, strict=True)}
    by = {
        str(k): [round(float(sum(v) / len(v)), 1) if v else None for v in r.by_draw]
        for k, r in zip(keys, rows, strict=True)
    }
    return {f"{name}_se": se, f"{name}_draws": by}


def table1(counts: list[int], rows: list[Row], seed: int) -> tuple[str, Figures]:
    """Table 1: Setup 1, 5 to 160 agents."""
    lines = [
        f"\nTable 1 — Setup 1 (40x40, 30 % obstacles, 20 x 1000, q_max 100); seed {seed}",
        f"{'agents':>6} | {'paper mean ± std':>18} | {'ours mean ± std':>18} | {'ours/paper':>10}"
        " | runs",
    ]
    for n, row in zip(counts, rows, strict=True):
        pm, ps = PAPER_T1.get(n, (math.nan, math.nan))
        lines.append(
            f"{n:>6} | {plus_minus(pm, ps, '9.1f', '7.1f')} | {cell(row)} | "
            f"{row.mean / pm:10.2f} | {runs(row)}"
        )
    std = {str(n): round(r.stats.sd, 1) for n, r in zip(counts, rows, strict=True)}
    figures = {"table1": _means(counts, rows), "table1_std": std}
    return "\n".join(lines), figures | _draws("table1", counts, rows)


def table2(counts: list[int], rows: list[Row], seed: int) -> tuple[str, Figures]:
    """Table 2: Setup 2, 1 to 8 agents, projected V_ref / n vs measured."""
    vref = rows[0].mean * counts[0]
    lines = [
        f"\nTable 2 — Setup 2 (20x20, 5 %, 2 x 1000); projected = V_ref/n; seed {seed}",
        f"{'agents':>6} | {'paper exp':>9} {'proj':>7} {'proj-exp':>8} | "
        f"{'ours exp':>9} {'proj':>8} {'proj-exp':>8} {'(%)':>6} | runs",
    ]
    for n, row in zip(counts, rows, strict=True):
        pe, pp = PAPER_T2.get(n, (math.nan, math.nan))
        proj = vref / n
        lines.append(
            f"{n:>6} | {pe:9.1f} {pp:7.1f} {pp - pe:8.1f} | {row.mean:9.1f} {proj:8.1f} "
            f"{proj - row.mean:8.1f} {100 * (proj - row.mean) / proj:6.1f} | {runs(row)}"
        )
    return "\n".join(lines), {"table2": _means(counts, rows)} | _draws("table2", counts, rows)


def table3(sizes: list[int], rows: dict[str, list[Row]], seed: int) -> tuple[str, Figures]:
    """Table 3 (c-marking) and, with ants among ``rows``, Figure 9: Setup 3, 50 agents."""
    cm = rows["cmarking"]
    lines = [
        "\nTable 3 — Setup 3 (5 %, 20 x 2000, 50 agents); R = ratio to the previous size;"
        f" seed {seed}",
        f"{'size':>8} | {'paper':>7} {'R':>5} | {'ours mean ± std':>18} {'R':>5} | runs",
    ]
    prev_p = prev_o = None
    for s, row in zip(sizes, cm, strict=True):
        p = PAPER_T3.get(s, math.nan)
        rp = f"{p / prev_p:5.2f}" if prev_p else "     "
        ro = f"{row.mean / prev_o:5.2f}" if prev_o else "     "
        lines.append(f"{f'{s}x{s}':>8} | {p:7.1f} {rp} | {cell(row)} {ro} | {runs(row)}")
        prev_p, prev_o = p, row.mean
    figures: Figures = {"table3": _means(sizes, cm)} | _draws("table3", sizes, cm)
    if "ants" in rows:
        lines.append(
            f"\nFigure 9 — c-marking vs ants, Setup 3; gap = (ants - c-marking) / ants; paper's "
            f"gaps shrink {'% → '.join(map(str, PAPER_FIG9_GAPS))}% with size; seed {seed}"
        )
        lines.append(f"{'size':>8} | {'c-marking':>18} | {'ants':>18} | {'gap':>5} | ants runs")
        for s, c, a in zip(sizes, cm, rows["ants"], strict=True):
            gap = 100 * (a.mean - c.mean) / a.mean if a.n else math.nan
            lines.append(f"{f'{s}x{s}':>8} | {cell(c)} | {cell(a)} | {gap:4.0f}% | {runs(a)}")
        figures["fig9"] = {
            "cmarking": figures["table3"],
            "ants": _means(sizes, rows["ants"]),
            "ants_unfinished": {
                str(s): r.unfinished for s, r in zip(sizes, rows["ants"], strict=True)
            },
        }
    return "\n".join(lines), figures


def no_nan(value: object) -> object:
    """The same structure with NaN (a row without a finished run) as null: strict JSON."""
    if isinstance(value, dict):
        return {k: no_nan(v) for k, v in value.items()}
    if isinstance(value, float) and math.isnan(value):
        return None
    return value
