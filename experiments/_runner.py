"""What the runners whose runs are saved per point share around their sweeps (``eyebot``,
``levy``): the options their command line ends with, where their runs are saved, and the lines
they print after each sweep and at the end."""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol, TypeVar

from ._common import Progress
from ._figures import add_figure_arguments
from ._saved import Executor, Made, add_saved_arguments, load_runs, run_pool

Record = dict[str, Any]


class SweepSettings(Protocol):
    """What :func:`run_points` reads of a runner's settings."""

    @property
    def seed(self) -> int: ...
    @property
    def runs(self) -> int: ...
    @property
    def workers(self) -> int: ...
    @property
    def executor(self) -> Executor: ...
    @property
    def save(self) -> Path | None: ...
    @property
    def progress(self) -> bool: ...


class NamedPoint(Protocol):
    """A point of a sweep: its runs are saved in ``<save>/<name>.jsonl``."""

    @property
    def name(self) -> str: ...


S = TypeVar("S", bound=SweepSettings)
P = TypeVar("P", bound=NamedPoint)


def add_runner_tail(
    parser: argparse.ArgumentParser, runner: str, run: Callable[[argparse.Namespace], int]
) -> None:
    """The options a runner's command line ends with (its saved runs: ``--save``,
    ``--no-save``, ``--json``, ``--quiet``, ``--executor``; its figures: ``--out``,
    ``--no-plots``, ``--format``), and ``run`` as what it does."""
    add_saved_arguments(parser, runner)
    add_figure_arguments(parser)
    parser.set_defaults(func=run)


def save_dir(args: argparse.Namespace) -> Path | None:
    """Where the runs are saved: ``--save``, or None with ``--no-save``."""
    save: Path | None = None if args.no_save else args.save
    return save


def sweep_made(
    label: str,
    made: Made,
    t0: float,
    wall: float,
    speed: Callable[[Made, float], str],
) -> str:
    """What a runner prints once a sweep (or figure) ``label`` begun at ``t0`` is done: the runs
    it made and the wall time, and (with runs made) ``speed(made, wall)``, their speed."""
    line = f"{label}: {made.runs} runs made in {time.monotonic() - t0:.0f} s wall"
    return f"{line}\n{speed(made, wall)}" if made.runs else line


def speed(simulated: float, cpu: float, wall: float, unit: str) -> str:
    """The speed of runs that took ``cpu`` s of their workers and ``wall`` s over the pool:
    ``simulated`` seconds of ``unit`` (robot-seconds, say) per wall second of a worker, and
    over the pool."""
    per_worker = simulated / cpu if cpu else math.nan
    overall = f", {simulated / wall:.0f} over the pool" if wall else ""
    return f"speed: {per_worker:.0f} simulated {unit} per wall second a worker{overall}"


def every_run(seed: int, records: Sequence[Record]) -> str:
    """The one JSON line of every run that ``--json`` ends the output with."""
    return json.dumps({"seed": seed, "runs": list(records)})


def saved_runs(s: SweepSettings, point: NamedPoint) -> dict[int, Record]:
    """The saved runs of ``point`` under the master seed of ``s``, by run index."""
    return load_runs(None if s.save is None else s.save / f"{point.name}.jsonl", s.seed)


def run_points(
    s: S,
    pts: Sequence[P],
    work: Callable[[tuple[S, P, int]], Record],
    made: Made,
    *,
    label: str,
    status: Callable[[Record], str],
    make: bool = True,
    mend: Callable[[P, dict[int, Record]], None] | None = None,
) -> tuple[list[Record], float]:
    """Every run of ``pts``: saved ones read back, missing ones (unless not ``make``) made by
    ``work((s, point, run))`` on ``s.workers`` processes, each told to ``made`` and saved as it
    finishes (kept as made when nothing is saved), read back with the rest, each point's runs
    passed to ``mend`` first. Returns the records of runs below ``s.runs`` and the wall
    seconds spent making them."""
    save = s.save
    before = {p: set(saved_runs(s, p)) for p in pts}
    jobs = [(s, p, k) for p in pts for k in range(s.runs) if k not in before[p]] if make else []
    kept: list[Record] = []  # the runs made, when no file keeps them

    def each(rec: Record) -> None:
        made(rec)
        if save is None:
            kept.append(rec)

    t0 = time.monotonic()
    run_pool(
        jobs,
        work,
        workers=s.workers,
        save_to=None if save is None else (lambda rec: save / f"{rec['point']}.jsonl"),
        bar=Progress(len(jobs), label, enabled=s.progress and bool(jobs)),
        status=status,
        on=s.executor,
        describe=lambda job: f"{job[1].name} run {job[2]} (--seed {job[0].seed})",
        each=each,
    )
    wall = time.monotonic() - t0
    have = {p: saved_runs(s, p) for p in pts}
    if mend is not None:
        for p in pts:
            mend(p, have[p])
    made_here = {(p, k) for _, p, k in jobs}
    records = [r for p in pts for k, r in sorted(have[p].items()) if (p, k) not in made_here]
    records += [have[p][k] for _, p, k in jobs] if save is not None else kept
    return [r for r in records if r["run"] < s.runs], wall
