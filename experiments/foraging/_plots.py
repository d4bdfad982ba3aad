"""The foraging experiment's figures: log-log iteration curves, ours (mean ± 1 se) beside the
paper's; matplotlib with the Agg backend, imported only when plotting."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from .._figures import count_axis, legend, pyplot, save


class Chart(NamedTuple):
    """One figure: its file name, the x values, one curve per series (``errors`` gives the
    standard errors of those that have them; the paper's have none), the axis label, the title."""

    name: str
    xs: list[int]
    series: dict[str, list[float]]
    errors: dict[str, list[float]]
    xlabel: str
    title: str


def plot(out_dir: Path, chart: Chart, fmt: str = "png") -> Path:
    """Write ``<name>.<fmt>`` of ``chart`` into ``out_dir``."""
    name, xs, series, errors, xlabel, title = chart
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, ys in series.items():
        es = errors.get(label)
        if es is None:
            ax.plot(xs, ys, marker="o", label=label)
        else:
            ax.errorbar(xs, ys, yerr=es, marker="o", capsize=3, label=label)
    ax.set_yscale("log")
    count_axis(ax, xs, log=True)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("iterations")
    ax.set_title(title)
    legend(ax, "se" if errors else None)
    ax.grid(True, which="both", alpha=0.3)
    return save(fig, out_dir, name, fmt)
