"""What the runners' figures share: matplotlib (Agg, imported only when plotting), the figure
options of every runner's command line, count axes, error-bar captions, and saving.

A figure says what its error bars are (one standard deviation, or one standard error of the
mean) in its legend's title; counts (agents, robots, targets) get integer ticks at the counts
measured, never overlapping; ``--format svg`` or ``pdf`` writes vector figures for papers. A
caption counts runs with :func:`runs_label` (1 run, 2 runs), and a table column takes one
precision for all its cells (:func:`shared_precision`).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

FORMATS = ("png", "svg", "pdf")
Spread = Literal["sd", "se"]
CAPTIONS = {"sd": "mean ± 1 sd", "se": "mean ± 1 se (standard error of the mean)"}


def add_figure_arguments(parser: argparse.ArgumentParser, default_out: str = "out") -> None:
    """``--out DIR``, ``--no-plots`` and ``--format png|svg|pdf``."""
    parser.add_argument(
        "--out", type=Path, default=Path(default_out), help=f"figure directory ({default_out})"
    )
    parser.add_argument("--no-plots", action="store_true", help="write no figures")
    parser.add_argument(
        "--format", choices=FORMATS, default="png", help="figure format (default png)"
    )


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def count_axis(ax: Any, counts: Sequence[float], axis: str = "x", log: bool = False) -> None:
    """Integer ticks at the measured ``counts`` (at most eight labelled, so none overlap)."""
    from matplotlib.ticker import FixedLocator, NullLocator, ScalarFormatter

    values = sorted({float(c) for c in counts})
    if not values:
        return
    if len(values) > 8:
        step = -(-len(values) // 8)
        values = values[::step] + ([values[-1]] if values[-1] not in values[::step] else [])
    target = ax.xaxis if axis == "x" else ax.yaxis
    if log:
        (ax.set_xscale if axis == "x" else ax.set_yscale)("log")
    target.set_major_locator(FixedLocator(values))
    target.set_minor_locator(NullLocator())
    formatter = ScalarFormatter()
    formatter.set_scientific(False)
    target.set_major_formatter(formatter)


def runs_label(n: int) -> str:
    """``"1 run"``, ``"5 runs"``: a count of runs for a caption or a panel's title."""
    return f"{n} run" if n == 1 else f"{n} runs"


def shared_precision(means: Sequence[float]) -> int:
    """Decimals for a whole table column (or row) of ``means``, so that one column does not
    mix precisions: 0 when the largest magnitude is 100 or more, 2 from 1, else 4."""
    top = max((abs(float(m)) for m in means), default=0.0)
    return 0 if top >= 100 else 2 if top >= 1 else 4


def legend(ax: Any, spread: Spread | None, **kwargs: Any) -> None:
    """The legend, titled with what the error bars are (``spread``; None: no error bars)."""
    ax.legend(title=None if spread is None else CAPTIONS[spread], **kwargs)


def save(fig: Any, out: Path, name: str, fmt: str = "png") -> Path:
    """Write ``<out>/<name>.<fmt>`` and close the figure."""
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.{fmt}"
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
