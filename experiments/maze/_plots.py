"""The maze experiment's figures, like the paper's Fig. 8 (metrics against agents) and Fig. 9
(composite index); matplotlib with the Agg backend, imported only when plotting."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._figures import count_axis, legend, pyplot, save
from ._paper import METRICS
from ._report import Records, Scores, group, probabilities


def plots(
    records: Records,
    scores: Scores,
    methods: list[str],
    agents: list[int],
    out: Path,
    fmt: str = "png",
) -> list[Path]:
    """Write ``maze_metrics`` (Fig. 8: mean ± 1 sd) and ``maze_composite`` (Fig. 9) into
    ``out``, as ``fmt`` files."""
    plt = pyplot()
    groups = group(records)
    ps = probabilities(records)
    shown = [m for m in METRICS if m[0] != "quality"]
    fig, axes = plt.subplots(
        len(shown), len(ps), figsize=(5 * len(ps), 2.6 * len(shown)), squeeze=False
    )
    for col, p in enumerate(ps):
        for row, (key, label, _) in enumerate(shown):
            ax = axes[row][col]
            for m in methods:
                xs = [n for n in agents if groups.get((p, m, n))]
                ys = [np.mean([r[key] for r in groups[(p, m, n)]]) for n in xs]
                es = [_sd([r[key] for r in groups[(p, m, n)]]) for n in xs]
                ax.errorbar(xs, ys, yerr=es, marker="o", ms=3, capsize=2, label=m)
            if key == "time_s":
                ax.set_yscale("log")
            ax.set_title(f"{label}\n{'given maze' if p is None else f'p = {p:g}'}", fontsize=8)
            ax.set_xlabel("agents", fontsize=8)
            count_axis(ax, agents)
    legend(axes[0][0], "sd", fontsize=7, title_fontsize=7)
    fig8 = save(fig, out, "maze_metrics", fmt)
    fig, axes = plt.subplots(1, len(ps), figsize=(5 * len(ps), 3.5), squeeze=False)
    for col, p in enumerate(ps):
        ax = axes[0][col]
        for m in methods:
            xs = [n for n in agents if n in scores[p].get(m, {})]
            ax.plot(xs, [scores[p][m][n] for n in xs], marker="o", label=m)
        ax.set_title(f"composite index, {'given maze' if p is None else f'p = {p:g}'}")
        ax.set_xlabel("agents")
        ax.set_ylabel("composite index (rank points)")
        count_axis(ax, agents)
    legend(axes[0][0], None, fontsize=7)
    return [fig8, save(fig, out, "maze_composite", fmt)]


def _sd(values: list[float]) -> float:
    return float(np.std(values, ddof=0)) if len(values) > 1 else 0.0  # as the tables
