"""The foraging experiment's figures: log-log iteration curves, ours beside the paper's
(matplotlib with the Agg backend, imported only when plotting)."""

from __future__ import annotations

from pathlib import Path


def plot(out_dir: Path, name: str, xs: list[int], series: dict[str, list[float]],
         xlabel: str, title: str) -> Path:  # fmt: skip
    """Write ``<name>.png`` into ``out_dir``: one curve per series."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for label, ys in series.items():
        ax.plot(xs, ys, marker="o", label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("iterations")
    ax.set_title(title)
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{name}.png"
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
