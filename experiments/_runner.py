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
from typing import Any

from ._figures import add_figure_arguments
from ._saved import Made, add_saved_arguments

Record = dict[str, Any]


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
