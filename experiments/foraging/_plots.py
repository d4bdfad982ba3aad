"""The foraging experiment's figures: log-log iteration curves, ours (mean ± 1 se) beside the
paper's; matplotlib with the Agg backend, imported only when plotting."""

from __future__ import annotations

from pathlib import Path

from .._figures import count_axis, legend, pyplot, save


def plot(
    out_dir: Path,
    name: str,
    xs: list[int],
    series: dict[str, list[float]],
    errors: dict[str, list[float]],
    xlabel: str,
    title: str,
    fmt: str = "png",
) -> Path:
    """Write ``<name>.<fmt>`` into ``out_dir``: one curve per series, with the standard errors
    ``errors`` gives for it (the paper's have none)."""
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
