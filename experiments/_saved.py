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
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

from mover.cli import UsageError

from ._common import Progress

Record = dict[str, Any]
Job = TypeVar("Job")

log = logging.getLogger(__name__)


def default_save(runner: str) -> Path:
    """Where ``runner`` saves its runs unless told: ``out/RUNNER/runs``, outside the tracked
    ``results/`` (the published runs are written only by an explicit ``--save results/...``)."""
    return Path("out") / runner / "runs"


def add_saved_arguments(parser: argparse.ArgumentParser, runner: str) -> None:
    """``--save DIR``, ``--no-save``, ``--json``, ``--quiet`` and ``--executor``: the options
    of a runner whose runs are saved per point (its ``--workers`` comes with ``--runs``, from
    ``_common``)."""
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
    add_executor_argument(parser)


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


EXECUTOR_HELP = (
    "where the runs are made: local (this machine's worker processes), dask (a Dask cluster "
    "of --workers processes started on 127.0.0.1) or dask://HOST:PORT (the Dask scheduler "
    "there; needs the dask extra)"
)


class JobFailed(UsageError):
    """A run raised: printed as one line naming the run and its seed, as a usage error is."""


@dataclass(frozen=True)
class Executor:
    """Where :func:`run_pool` makes the runs: ``local`` (a fork pool), or ``dask`` at
    ``address`` (None: a ``LocalCluster`` on 127.0.0.1)."""

    kind: str = "local"
    address: str | None = None


def executor(text: str) -> Executor:
    """``--executor local|dask[://ADDRESS]`` read (argparse type): ``dask://HOST:PORT`` is
    the scheduler at ``tcp://HOST:PORT``; ``dask://tls://HOST:PORT`` keeps its scheme."""
    if text == "local":
        return Executor()
    if text == "dask":
        return Executor("dask")
    if text.startswith("dask://") and len(text) > len("dask://"):
        rest = text[len("dask://") :]
        return Executor("dask", rest if "://" in rest else f"tcp://{rest}")
    raise argparse.ArgumentTypeError(f"expected local, dask or dask://HOST:PORT, got {text!r}")


def add_executor_argument(parser: argparse.ArgumentParser) -> None:
    """``--executor local|dask[://ADDRESS]`` (default local)."""
    parser.add_argument(
        "--executor", type=executor, default=Executor(), metavar="WHERE", help=EXECUTOR_HELP
    )


class Made:
    """A running aggregate of the runs a sweep made, for its caller's report: how many, and
    the sum of each ``measures`` value over them (the runs themselves are in the save file).
    Called with each record (:func:`run_pool`'s ``each``)."""

    def __init__(self, **measures: Callable[[Record], float]) -> None:
        self.measures = measures
        self.runs = 0
        self.sums = dict.fromkeys(measures, 0.0)

    def __call__(self, rec: Record) -> None:
        self.runs += 1
        for name, measure in self.measures.items():
            self.sums[name] += measure(rec)


def run_pool(
    jobs: Sequence[Job],
    work: Callable[[Job], Record],
    *,
    workers: int,
    save_to: Callable[[Record], Path] | None,
    bar: Progress,
    status: Callable[[Record], str],
    on: Executor | None = None,
    describe: Callable[[Job], str] = str,
    each: Callable[[Record], None] | None = None,
) -> int:
    """Make ``jobs`` with ``work`` on ``workers`` forked processes (one: in this one), or on
    the Dask cluster ``on`` names; append each record to the file ``save_to(record)`` as it
    comes, this process being the only writer (None: no file), and hand it to ``each`` (a
    running aggregate such as :class:`Made`, or the caller's list when nothing is saved).
    Nothing is kept here: the caller builds its tables from the saved files (or what ``each``
    kept). Returns the number of runs made. A job that raises stops the sweep:
    :class:`JobFailed` names it (``describe``)."""
    made = 0
    on = on or Executor()
    batch = _Batch(jobs, work, describe)
    records = _local(batch, workers) if on.kind == "local" else _dask(batch, workers, on.address)
    for rec in records:
        made += 1
        if save_to is not None:
            path = save_to(rec)
            path.parent.mkdir(parents=True, exist_ok=True)
            with path.open("a") as f:
                f.write(json.dumps(rec) + "\n")
        if each is not None:
            each(rec)
        bar.update(made, status(rec))
    bar.close(made)
    return made


@dataclass(frozen=True)
class _Batch(Generic[Job]):
    """What an executor is handed: the jobs, the work that makes a job's record, and how a job
    is named when it fails."""

    jobs: Sequence[Job]
    work: Callable[[Job], Record]
    describe: Callable[[Job], str]

    def failed(self, job: Job, error: str) -> JobFailed:
        """The error that stops the sweep: ``job`` raised ``error`` (its type and message)."""
        return JobFailed(f"{self.describe(job)} raised {error}")


def _local(batch: _Batch[Job], workers: int) -> Iterator[Record]:
    guarded = _Guarded(batch.work)
    if workers <= 1:  # in this process: no fork for a single worker
        made: Iterator[tuple[int, Record | str]] = map(guarded, enumerate(batch.jobs))
        yield from _or_fail(made, batch)
        return
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(max(1, workers), initializer=_worker) as pool:
        made = pool.imap_unordered(guarded, enumerate(batch.jobs), chunksize=1)
        yield from _or_fail(made, batch)


class _Guarded:
    """``work`` made to return ``(index, record)``, or ``(index, what it raised)`` as text, so
    that the runner can name the job that failed (a pool says only what was raised)."""

    def __init__(self, work: Callable[[Any], Record]) -> None:
        self.work = work

    def __call__(self, indexed: tuple[int, Any]) -> tuple[int, Record | str]:
        index, job = indexed
        try:
            return index, self.work(job)
        except Exception as exc:
            return index, f"{type(exc).__name__}: {exc}"


def _or_fail(made: Iterator[tuple[int, Record | str]], batch: _Batch[Job]) -> Iterator[Record]:
    for index, rec in made:
        if isinstance(rec, str):
            raise batch.failed(batch.jobs[index], rec)
        yield rec


CONNECT_S = 30.0
"""The longest wait for a Dask scheduler to answer."""


def _dask(batch: _Batch[Job], workers: int, address: str | None) -> Iterator[Record]:
    """The records of the batch's jobs as the cluster finishes them. A worker that dies is replaced
    and its jobs rerun by the scheduler (Dask's ``allowed-failures``); a job that raises is
    not retried: the others are cancelled and :class:`JobFailed` names it."""
    try:
        import distributed as dask  # the dask extra, imported only when asked for
    except ImportError:
        raise UsageError(
            "--executor dask needs the dask extra: pip install 'mover[dask]'"
        ) from None
    with ExitStack() as stack:
        if address is None:
            cluster = dask.LocalCluster(
                n_workers=max(1, workers),
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                # the scheduler's HTTP server starts whatever the dashboard setting: None
                # means port 8787 (on every interface, a warning when taken); a free port
                # on loopback, with no dashboard, instead
                dashboard_address="127.0.0.1:0",
                scheduler_kwargs={"dashboard": False},
            )
            stack.enter_context(cluster)
            client = stack.enter_context(dask.Client(cluster, timeout=CONNECT_S))
        else:
            try:
                client = stack.enter_context(dask.Client(address, timeout=CONNECT_S))
            except OSError as exc:
                raise UsageError(f"--executor: no Dask scheduler at {address}: {exc}") from None
        futures = {client.submit(batch.work, job, pure=False): job for job in batch.jobs}
        for future in dask.as_completed(list(futures)):
            job = futures.pop(future)
            try:
                rec = future.result()
            except Exception as exc:
                client.cancel(list(futures))
                raise batch.failed(job, f"{type(exc).__name__}: {exc}") from None
            future.release()
            yield rec


def _worker() -> None:
    """A worker leaves Ctrl-C to the runner (which stops the pool) and ends at once on the
    SIGTERM the pool stops it with: a forked worker would otherwise inherit the command's
    handler (``mover.cli.interrupt_on_sigterm``) and print a traceback as the pool closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
