"""CU-LVP against the authors' reference code, paired per maze: ours minus theirs, in rounds.

``python -m experiments.maze.compare_reference OURS REFERENCE [SEEDS [SUFFIX]]`` prints the
table of ``results/README.md``. OURS holds one ``--save`` directory per seed (``OURS/2026/...``,
from ``python -m experiments.maze --runs 100 --seed 2026 --methods cu-lvp --agents 4,8 --p
0.85,0.15 --no-plots --save OURS/2026``); SUFFIX, the end of our runs' file names for other
settings (``-wholenews``, ``-nonews``). REFERENCE holds ``ref-s<seed>.jsonl``, one JSON line per run
(``p``, ``run``, ``agents``, ``rounds``) of the reference code on the same mazes and starts.
The reference code itself is not in this repository: its authors publish it without a license.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

SEEDS = (2026, 2027, 2028, 2029, 2030)
CELLS = ((0.85, 4), (0.85, 8), (0.15, 4), (0.15, 8))


def _ours(root: Path, seed: int, p: float, n: int, suffix: str) -> dict[int, int]:
    path = root / str(seed) / f"cu-lvp-n{n}-s30-p{p:g}-x3{suffix}.jsonl"
    if not path.exists():
        return {}
    rows = (json.loads(line) for line in path.read_text().splitlines() if line.strip())
    return {int(r["run"]): int(r["rounds"]) for r in rows if "rounds" in r}


def _reference(root: Path, seed: int, p: float, n: int) -> dict[int, int]:
    path = root / f"ref-s{seed}.jsonl"
    if not path.exists():
        return {}
    rows = (json.loads(line) for line in path.read_text().splitlines() if line.strip())
    return {int(r["run"]): int(r["rounds"]) for r in rows if r["p"] == p and r["agents"] == n}


def table(ours: Path, reference: Path, seeds: tuple[int, ...] = SEEDS, suffix: str = "") -> str:
    """The paired table, one row per cell: mean ± SE per seed and over all, the means, the
    share of rounds saved, and how many mazes ours needed fewer / equal / more rounds."""
    head = "| p | agents | " + " | ".join(map(str, seeds)) + " | all | ours / reference |"
    lines = [head + " % fewer | ours fewer / equal / more |", "|---" * (len(seeds) + 6) + "|"]
    for p, n in CELLS:
        cells, diff, mine, theirs = [], [], [], []
        for seed in seeds:
            a, b = _ours(ours, seed, p, n, suffix), _reference(reference, seed, p, n)
            runs = sorted(set(a) & set(b))
            d = np.array([a[k] - b[k] for k in runs], dtype=float)
            cells.append(_mean_se(d))
            diff += d.tolist()
            mine += [a[k] for k in runs]
            theirs += [b[k] for k in runs]
        d = np.array(diff)
        if len(d) < 2:
            lines.append(f"| {p} | {n} | " + " | ".join(cells) + " | – | – | – | – |")
            continue
        saved = 100 * (np.mean(theirs) - np.mean(mine)) / np.mean(theirs)
        lines.append(
            f"| {p} | {n} | "
            + " | ".join(cells)
            + f" | **{_mean_se(d)}** | {np.mean(mine):.1f} / {np.mean(theirs):.1f} | "
            + f"{saved:.1f} % | {(d < 0).sum()} / {(d == 0).sum()} / {(d > 0).sum()} |"
        )
    return "\n".join(lines)


def _mean_se(d: np.ndarray) -> str:
    if len(d) < 2:
        return "–"
    text = f"{d.mean():+.1f} ± {d.std(ddof=1) / np.sqrt(len(d)):.1f}"
    return text if len(d) in (100, 500) else f"{text} ({len(d)})"


def main(argv: list[str]) -> int:
    """Print the table; a one-line error for bad arguments."""
    if len(argv) not in (2, 3, 4):
        print("usage: python -m experiments.maze.compare_reference OURS REFERENCE [SEEDS [SUFFIX]]")
        return 2
    try:
        seeds = tuple(int(s) for s in argv[2].split(",")) if len(argv) >= 3 else SEEDS
    except ValueError:
        print(f"compare_reference: SEEDS must be a comma list of integers, not {argv[2]!r}")
        return 2
    print(table(Path(argv[0]), Path(argv[1]), seeds, argv[3] if len(argv) == 4 else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
