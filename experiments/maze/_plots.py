"""The maze experiment's figures, like the paper's Fig. 8 (metrics against agents) and Fig. 9
(composite index); matplotlib with the Agg backend, imported only when plotting."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._paper import METRICS
from ._report import Records, Scores, group, probabilities


def plots(
    records: Records, scores: Scores, methods: list[str], agents: list[int], out: Path
) -> list[Path]:
    """Write ``maze_metrics.png`` (Fig. 8) and ``maze_composite.png`` (Fig. 9) into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
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
                es = [np.std([r[key] for r in groups[(p, m, n)]]) for n in xs]
                ax.errorbar(xs, ys, yerr=es, marker="o", ms=3, capsize=2, label=m)
            if key == "time_s":
                ax.set_yscale("log")
            ax.set_title(f"{label}\n{'given maze' if p is None else f'p = {p:g}'}", fontsize=8)
            ax.set_xlabel("agents", fontsize=8)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig8 = out / "maze_metrics.png"
    fig.savefig(fig8, dpi=110)
    plt.close(fig)
    fig, axes = plt.subplots(1, len(ps), figsize=(5 * len(ps), 3.5), squeeze=False)
    for col, p in enumerate(ps):
        ax = axes[0][col]
        for m in methods:
            xs = [n for n in agents if n in scores[p].get(m, {})]
            ax.plot(xs, [scores[p][m][n] for n in xs], marker="o", label=m)
        ax.set_title(f"composite index, {'given maze' if p is None else f'p = {p:g}'}")
        ax.set_xlabel("agents")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig9 = out / "maze_composite.png"
    fig.savefig(fig9, dpi=110)
    plt.close(fig)
    return [fig8, fig9]
