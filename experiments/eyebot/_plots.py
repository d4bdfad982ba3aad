"""The eye-bot experiment's figures, like the paper's Fig. 2-5; matplotlib (Agg), imported only
when plotting. Error bars are one standard deviation, as the paper's (the legends say so)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .._figures import count_axis, legend, pyplot, runs_label, save
from ._report import BINS, Records, fig3_panels, fig4_panels, histogram


def plot(figure: str, records: Records, out: Path, fmt: str = "png") -> Path | None:
    """Write ``eyebot_<figure>.<fmt>``; None when the records have nothing to draw."""
    plt = pyplot()
    draw = {"fig2": _fig2, "fig3": _hists, "fig4": _hists, "fig5": _fig5, "beyond": _beyond}
    fig = draw[figure](plt, records, figure)
    if fig is None:
        return None
    return save(fig, out, f"eyebot_{figure}", fmt)


def _fig2(plt, records: Records, _figure: str):  # type: ignore[no-untyped-def]
    rows = [r for r in records if r["arena"] == "eyebot-cluttered"]
    if not rows:
        return None
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    drawn = 0
    for key, way, label in (
        ("t_1", "learning", "t_1 (first arrival)"),
        ("t_a", "learning", "t_a (learning)"),
        ("t_a_all", "shortest", "t_s (shortest way shown)"),
    ):
        ns = sorted({r["footbots"] for r in rows if r["eyebots"] == way})
        vals = [
            [r[key] for r in rows if r["footbots"] == n and r["eyebots"] == way and r[key]]
            for n in ns
        ]
        keep = [(n, v) for n, v in zip(ns, vals, strict=True) if v]
        if not keep:
            continue
        xs = [n for n, _ in keep]
        ys = [float(np.mean(v)) for _, v in keep]
        es = [float(np.std(v, ddof=1)) if len(v) > 1 else 0.0 for _, v in keep]
        ax.errorbar(xs, ys, yerr=es, marker="o", ms=4, capsize=3, label=label)
        drawn += 1
    if not drawn:
        plt.close(fig)
        return None
    _by_footbots(ax, rows, "time (simulated s)", "Fig. 2: travel times, cluttered arena")
    return fig


def _hists(plt, records: Records, figure: str):  # type: ignore[no-untyped-def]
    panels: list[tuple[str, list[float]]] = (
        fig3_panels(records)
        if figure == "fig3"
        else [(f"{n} foot-bots", rhos) for n, rhos in fig4_panels(records)]
    )
    if not panels:
        return None
    fig, axes = plt.subplots(1, len(panels), figsize=(2.0 * len(panels) + 1, 2.6), sharey=True)
    axes = np.atleast_1d(axes)
    centres = (np.arange(BINS) + 0.5) / BINS
    for ax, (title, rhos) in zip(axes, panels, strict=True):
        ax.bar(centres, histogram(rhos), width=0.9 / BINS)
        ax.set_title(f"{title} ({runs_label(len(rhos))})", fontsize=8)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.set_xlabel("ρ")
    axes[0].set_ylabel("fraction of runs")
    return fig


def _fig5(plt, records: Records, _figure: str):  # type: ignore[no-untyped-def]
    rows = [
        r
        for r in records
        if r["arena"] == "double-corridor-r1" and r["footbots"] >= 10 and r["rho"] is not None
    ]
    rows = [r for r in rows if r["t_a"]]
    if not rows:
        return None
    fig, ax = plt.subplots(figsize=(5.0, 3.6))
    for n in sorted({r["footbots"] for r in rows}):
        mine = [r for r in rows if r["footbots"] == n]
        ax.scatter([r["rho"] for r in mine], [r["t_a"] for r in mine], s=10, label=f"{n} foot-bots")
    ax.set_xlabel("ρ")
    ax.set_ylabel("t_a (simulated s)")
    ax.set_title("Fig. 5: travel time against ρ, equal corridors", fontsize=9)
    legend(ax, None, fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def _beyond(plt, records: Records, _figure: str):  # type: ignore[no-untyped-def]
    rows = [r for r in records if r["arena"] == "double-corridor-r1.5" and r["t_a"]]
    if not rows:
        return None
    fig, ax = plt.subplots(figsize=(5.0, 3.6))
    for way in ("learning", "weigh"):  # rows is not empty: at least one of them is drawn
        ns = sorted({r["footbots"] for r in rows if r["eyebots"] == way})
        vals = [[r["t_a"] for r in rows if r["footbots"] == n and r["eyebots"] == way] for n in ns]
        if ns:
            ax.errorbar(
                ns,
                [float(np.mean(v)) for v in vals],
                yerr=[float(np.std(v, ddof=1)) if len(v) > 1 else 0.0 for v in vals],
                marker="o",
                capsize=3,
                label="trip-time weights" if way == "weigh" else "the paper's learning",
            )
    _by_footbots(ax, rows, "t_a (simulated s)", "Beyond the paper: unequal corridors, r = 1.5")
    return fig


def _by_footbots(ax: Any, rows: Records, ylabel: str, title: str) -> None:
    """Label an axis of times against the foot-bot count, with the counts of ``rows`` as ticks."""
    ax.set_xlabel("foot-bots")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    count_axis(ax, sorted({r["footbots"] for r in rows}))
    legend(ax, "sd", fontsize=8, title_fontsize=8)
    ax.grid(alpha=0.3)
