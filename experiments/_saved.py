"""Runs saved one JSON object a line, resumed by a later invocation, made on a pool of workers.

A runner keeps each point's runs in a JSON-lines file, appended as they finish. A later
invocation with the same master seed reads them back (:func:`load_runs`) and makes only the
missing ones (:func:`run_pool`), so that trials can be added to a point across sessions.
"""

from __future__ import annotations

import argparse
import json
import logging
import multiprocessing
import signal
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from ._common import Progress

Record = dict[str, Any]
Job = TypeVar("Job")

log = logging.getLogger(__name__)


def default_save(runner: str) -> Path:
    """Where ``runner`` saves its runs unless told: ``out/RUNNER/runs``, outside the tracked
    ``results/`` (the published runs are written only by an explicit ``--save results/...``)."""
    return Path("out") / runner / "runs"


def add_saved_arguments(parser: argparse.ArgumentParser, runner: str) -> None:
    """``--save DIR``, ``--no-save``, ``--json`` and ``--quiet``: the options of a runner whose
    runs are saved per point (its ``--workers`` comes with ``--runs``, from ``_common``)."""
    where = default_save(runner)
    parser.add_argument(
        "--save",
        type=Path,
        default=where,
        help=f"per-point JSON-lines directory, read back and added to (default {where}; the "
        "published runs: --save results/" + runner + "/runs)",
    )
    parser.add_argument("--no-save", action="store_true", help="keep no per-point files")
    parser.add_argument("--json", action="store_true", help="end with one JSON line of every run")
    parser.add_argument("--quiet", action="store_true", help="no progress line")


def load_runs(path: Path | None, seed: int) -> dict[int, Record]:
    """The runs saved in ``path`` under master ``seed``, by run index (a line that does not
    parse, the last one of a run cut short say, is skipped with a warning)."""
    if path is None or not path.exists():
        return {}
    got: dict[int, Record] = {}
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
            if rec.get("seed") == seed:
                got[int(rec["run"])] = rec
        except (ValueError, KeyError, TypeError, AttributeError):
            log.warning("%s:%d: not a saved run, skipped", path, number)
    return got


def saved_seeds(folder: Path) -> dict[int, dict[str, int]]:
    """The master seeds whose runs ``folder`` holds: per seed, the runs saved per point (the
    file's stem), read as :func:`load_runs` reads them."""
    seeds: dict[int, dict[str, int]] = {}
    for path in sorted(folder.glob("*.jsonl")) if folder.is_dir() else []:
        for line in path.read_text().splitlines():
            try:
                seed = json.loads(line)["seed"]
            except (ValueError, KeyError, TypeError):
                continue  # load_runs names it when the runs are read
            if isinstance(seed, int):
                per = seeds.setdefault(seed, {})
                per[path.stem] = per.get(path.stem, 0) + 1
    return dict(sorted(seeds.items()))


def seeds_table(folder: Path) -> str:
    """What ``--saved`` without ``--seed`` prints: each saved seed with its points' run counts."""
    seeds = saved_seeds(folder)
    if not seeds:
        return f"no runs saved in {folder}"
    lines = [f"seeds saved in {folder} (pick one with --seed N):"]
    for seed, per in seeds.items():
        counts = ", ".join(f"{point} {n}" for point, n in per.items())
        lines.append(f"  {seed}: {sum(per.values())} runs ({counts})")
    return "\n".join(lines)


def run_pool(
    jobs: Sequence[Job],
    work: Callable[[Job], Record],
    *,
    workers: int,
    save_to: Callable[[Record], Path] | None,
    bar: Progress,
    status: Callable[[Record], str],
) -> list[Record]:
    """Make ``jobs`` with ``work`` on ``workers`` forked processes; append each record to the
    file ``save_to(record)`` as it comes (None: keep nothing). Returns the records made."""
    fresh: list[Record] = []
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(max(1, workers), initializer=_worker) as pool:
        for rec in pool.imap_unordered(work, jobs, chunksize=1):
            fresh.append(rec)
            if save_to is not None:
                path = save_to(rec)
                path.parent.mkdir(parents=True, exist_ok=True)
                with path.open("a") as f:
                    f.write(json.dumps(rec) + "\n")
            bar.update(len(fresh), status(rec))
    bar.close(len(fresh))
    return fresh


def _worker() -> None:
    """A worker leaves Ctrl-C to the runner (which stops the pool) and ends at once on the
    SIGTERM the pool stops it with: a forked worker would otherwise inherit the command's
    handler (``mover.cli.interrupt_on_sigterm``) and print a traceback as the pool closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
