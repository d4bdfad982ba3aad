"""The Lévy experiment's figures, like the paper's Fig. 8 (search time against targets) and
Fig. 9 (against robots), and the α sweep; matplotlib with the Agg backend, imported only when
plotting."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robots.library import stable_alpha

from .._figures import count_axis, legend, pyplot, save
from ._paper import ALPHA_TARGETS, ORDER, Setup
from ._report import Records, estimate, times

_LABELS = {"fig8": "targets", "fig9": "robots", "alpha": "alpha"}
_TITLES = {
    "fig8": "search time vs targets, 10 robots (Fig. 8)",
    "fig9": "search time vs robots, 8 targets (Fig. 9)",
    "alpha": "search time vs stable index α, 10 robots, 8 targets",
}


def plot(sweep: str, records: Records, setup: Setup, out: Path, fmt: str = "png") -> Path:
    """Write ``levy_<sweep>.<fmt>``: mean search time ± se per method."""
    plt = pyplot()
    key = _LABELS[sweep]
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for m in ORDER:
        mine = [r for r in records if r["method"] == m]
        xs = sorted({r[key] for r in mine})
        if not xs:
            continue
        ts = [times([r for r in mine if r[key] == x], setup.max_time) for x in xs]
        ys = [float(np.mean(t)) for t in ts]
        es = [float(np.std(t, ddof=1) / np.sqrt(len(t))) if len(t) > 1 else 0.0 for t in ts]
        ax.errorbar(xs, ys, yerr=es, marker="o", ms=4, capsize=3, label=m)
    if sweep == "fig9":  # log-log: the ideal T(1)/n of the Lévy walk is a straight line
        lone = [r for r in records if r["method"] == "L" and r["robots"] == 1]
        ns = sorted({r["robots"] for r in records})
        if lone and len(ns) > 1:
            t1 = float(np.mean(times(lone, setup.max_time)))
            ax.plot(ns, [t1 / n for n in ns], "k:", lw=1, label="L: T(1)/n")
        ax.set_yscale("log")
    if sweep != "alpha":
        count_axis(ax, sorted({r[key] for r in records}), log=sweep == "fig9")
    if sweep == "alpha":
        mu = estimate(setup, ALPHA_TARGETS)[1]
        ax.axvline(stable_alpha(mu), color="k", ls=":", lw=1, label="eq. 4-5 (non-destructive)")
    ax.set_xlabel(key)
    ax.set_ylabel("time to find all targets (s)")
    ax.set_title(_TITLES[sweep], fontsize=9)
    legend(ax, "se", fontsize=8, title_fontsize=8)
    ax.grid(alpha=0.3)
    return save(fig, out, f"levy_{sweep}", fmt)
