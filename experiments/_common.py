"""What the experiment runners share: the progress line, mean ± sd / se, comma lists, and
their ``--runs``, ``--seed`` and ``--workers`` (and the check that their output folders can be
written, made with those, before any run: a bad ``--out`` used to be found after the runs).

One copy each (the runners had written their own). The progress line goes to stderr, so
that stdout holds only the report, the same for the same seeds.
"""

from __future__ import annotations

import argparse
import math
import secrets
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np

from mover.cli import MAX_SEED, UsageError, bounded

T = TypeVar("T")


@dataclass(frozen=True)
class Summary:
    """Mean, standard deviation (``ddof`` as asked) and count of some measurements."""

    n: int
    mean: float
    sd: float

    @property
    def se(self) -> float:
        """Standard error of the mean (nan for fewer than two values)."""
        return self.sd / math.sqrt(self.n) if self.n > 1 else math.nan

    @property
    def rel_se(self) -> float:
        """Standard error as a fraction of the mean (inf for fewer than two values)."""
        return self.se / self.mean if self.n > 1 else math.inf


def summary(values: Sequence[float], ddof: int = 1) -> Summary:
    """:class:`Summary` of ``values``: nan mean without values, nan sd without ``ddof + 1``."""
    n = len(values)
    mean = float(np.mean(values)) if n else math.nan
    sd = float(np.std(values, ddof=ddof)) if n > ddof else math.nan
    return Summary(n, mean, sd)


def plus_minus(mean: float, sd: float, spec: str, sd_spec: str | None = None) -> str:
    """``mean ±sd``, each number in its format spec (``sd_spec``: ``spec`` after a space)."""
    return f"{mean:{spec}} ±{sd:{' ' + spec if sd_spec is None else sd_spec}}"


def comma_list(
    kind: Callable[[str], T], choices: Iterable[T] | None = None
) -> Callable[[str], list[T]]:
    """An argparse ``type`` for ``--agents 4,8``: a non-empty comma list of ``kind``, each one
    of ``choices`` if given."""
    allowed = None if choices is None else list(choices)

    def parse(text: str) -> list[T]:
        try:
            items = [kind(t) for t in text.split(",") if t.strip()]
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        if allowed is not None:
            bad = [i for i in items if i not in allowed]
            if bad:
                raise argparse.ArgumentTypeError(
                    f"unknown {bad[0]!r}; choose from {', '.join(map(str, allowed))}"
                )
        if not items:
            raise argparse.ArgumentTypeError("empty list")
        return items

    return parse


ListOption = tuple[str, Callable[[str], Sequence[object]], Iterable[object], str]
"""A comma-list option: its flag, its :func:`comma_list` type, its default and its help."""


def add_list_arguments(parser: argparse.ArgumentParser, *options: ListOption) -> None:
    """Add comma-list options to ``parser``, in the order given (each default a fresh list)."""
    for flag, parse, default, what in options:
        parser.add_argument(flag, type=parse, default=list(default), help=what)


def shown(default: Iterable[float]) -> str:
    """``(default 1,2,4)``: a comma-list option's default as its help shows it."""
    return f"(default {','.join(f'{v:g}' for v in default)})"


class Progress:
    """Progress on stderr: on a terminal, a bar on one line (``label [####....] done/total eta
    status``) redrawn at most twice a second; elsewhere (a log file, CI) plain lines, one at
    each tenth of the work done or every 30 s, whichever comes first.
    """

    def __init__(
        self,
        total: int,
        label: str = "",
        width: int = 30,
        enabled: bool = True,
        terminal: bool | None = None,
    ) -> None:
        self.total, self.label, self.width, self.enabled = total, label, width, enabled
        self.terminal = sys.stderr.isatty() if terminal is None else terminal
        self.t0 = time.monotonic()
        self._drawn = -math.inf
        self._tenth = 0

    def update(self, done: int, status: str = "", force: bool = False) -> None:
        """Show ``done`` of ``total`` with ``status`` after it."""
        if not self.enabled:
            return
        now = time.monotonic()
        eta = (now - self.t0) / max(done, 1) * max(self.total - done, 0)
        if not self.terminal:
            tenth = 10 * min(done, self.total) // max(self.total, 1)
            if force or tenth > self._tenth or now - self._drawn >= 30.0:
                self._tenth, self._drawn = tenth, now
                label = f"{self.label}: " if self.label else ""
                sys.stderr.write(f"{label}{done}/{self.total} done, eta {eta:.0f} s  {status}\n")
                sys.stderr.flush()
            return
        if not force and now - self._drawn < 0.5:
            return
        self._drawn = now
        fill = int(self.width * min(done, self.total) / max(self.total, 1))
        label = f"{self.label:<22} " if self.label else ""
        sys.stderr.write(
            f"\r{label}[{'#' * fill}{'.' * (self.width - fill)}] {done:>4}/{self.total:<4}"
            f" eta {eta:5.0f}s  {status:<40}"
        )
        sys.stderr.flush()

    def close(self, done: int, status: str = "") -> None:
        """Draw the last state (and end the bar's line)."""
        if self.enabled:
            self.update(done, status, force=True)
            if self.terminal:
                sys.stderr.write("\n")


def runner_parser(
    sub: argparse._SubParsersAction[argparse.ArgumentParser],
    name: str,
    help: str,
    doc: str | None,
) -> argparse.ArgumentParser:
    """The sub-parser of one experiment runner, its module docstring as the description."""
    return sub.add_parser(
        name, help=help, description=doc, formatter_class=argparse.RawDescriptionHelpFormatter
    )


MAX_RUNS = 100_000
"""The most runs a point (row, cell) may be given."""
MAX_WORKERS = 64
"""The most worker processes a runner may start."""


def add_run_arguments(
    parser: argparse.ArgumentParser,
    *,
    runs: int | None,
    seed: int | None,
    workers: int | None = None,
    runs_default: str | None = None,
) -> None:
    """``--runs N``, ``--seed N`` and (unless ``workers`` is None) ``--workers N``, with the
    runner's defaults (``seed`` None: a random one; ``runs_default`` says what a ``runs`` of
    None means). :func:`read_run_arguments` checks them."""
    said = f"default {runs}" if runs_default is None else f"default: {runs_default}"
    parser.add_argument("--runs", type=int, default=runs, help=f"runs per point ({said})")
    said = "default: random" if seed is None else f"default {seed}"
    parser.add_argument("--seed", type=int, default=seed, help=f"master seed ({said})")
    if workers is not None:
        parser.add_argument(
            "--workers", type=int, default=workers, help=f"worker processes (default {workers})"
        )


@dataclass(frozen=True)
class RunArguments:
    """:func:`add_run_arguments`' options, checked: runs (None: the runner decides), the
    master seed (drawn when not given), worker processes (1 for a runner without)."""

    runs: int | None
    seed: int
    workers: int


def read_run_arguments(args: argparse.Namespace) -> RunArguments:
    """The checked ``--runs``, ``--seed`` and ``--workers`` of ``args`` (a seed drawn at random
    when none was given), and the output folders the runner will write (``--out`` unless
    ``--no-plots``, ``--save`` unless ``--no-save``) checked by :func:`writable_dir`; raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    runs = None if args.runs is None else _checked("--runs", args.runs, 1, MAX_RUNS)
    seed = secrets.randbits(32) if args.seed is None else _checked("--seed", args.seed, 0, MAX_SEED)
    workers = getattr(args, "workers", None)
    workers = 1 if workers is None else _checked("--workers", workers, 1, MAX_WORKERS)
    for option, skip in (("out", "no_plots"), ("save", "no_save")):
        if getattr(args, option, None) is not None and not getattr(args, skip, False):
            writable_dir(Path(getattr(args, option)), f"--{option}")
    return RunArguments(runs, seed, workers)


def writable_dir(path: Path, option: str) -> Path:
    """``path`` if it is a directory this process can write in, or can be made one (it need
    not exist yet: nothing is made); else :class:`~mover.cli.UsageError` naming ``option``.
    Checked by writing a file in the nearest folder that exists (root may write where
    ``os.access`` says no one can, and no one can write in /proc)."""
    probe = path
    while not probe.exists() and probe.parent != probe:
        probe = probe.parent
    if not probe.is_dir():
        raise UsageError(f"{option} {path}: {probe} is not a directory")
    try:
        with tempfile.NamedTemporaryFile(dir=probe, prefix=".mover-probe-"):
            pass
    except OSError as exc:
        raise UsageError(f"{option} {path}: cannot write in {probe}: {exc.strerror}") from None
    return path


def _checked(option: str, value: int, low: int, high: int) -> int:
    try:
        return bounded(int, low, high)(str(value))
    except argparse.ArgumentTypeError as exc:  # the wording of every bounded option
        raise UsageError(f"{option} {exc}") from None
