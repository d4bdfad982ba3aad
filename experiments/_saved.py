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


def add_saved_arguments(parser: argparse.ArgumentParser, default_save: str) -> None:
    """``--save DIR``, ``--no-save``, ``--json`` and ``--quiet``: the options of a runner whose
    runs are saved per point (its ``--workers`` comes with ``--runs``, from ``_common``)."""
    parser.add_argument(
        "--save",
        type=Path,
        default=Path(default_save),
        help=f"per-point JSON-lines directory, read back and added to (default {default_save})",
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
