"""`mover experiment NAME ...`: the frame for experiment runners.

Each runner registers itself under the ``mover.experiments`` entry-point group with a
``register(subparsers)`` function that adds its own sub-parser and sets ``func`` (a callable
taking the parsed arguments and returning an exit code, raising
:class:`~mover.cli.UsageError` for a command-line mistake). ``python -m experiments.NAME``
runs one runner without the ``mover`` command (:func:`main`).
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable, Sequence
from importlib.metadata import entry_points

from mover.cli import UsageError

log = logging.getLogger(__name__)

Register = Callable[["argparse._SubParsersAction[argparse.ArgumentParser]"], None]


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``experiment`` verb and gather the experiment runners under it."""
    parser = sub.add_parser("experiment", help="run a paper's experiment in-process, seeded")
    runners = parser.add_subparsers(dest="experiment", metavar="NAME", required=True)
    for ep in sorted(entry_points(group="mover.experiments"), key=lambda e: e.name):
        try:
            ep.load()(runners)
        except Exception as exc:  # a broken runner must not break the others
            log.debug("experiment %r is unavailable: %s", ep.name, exc)


def main(name: str, register: Register, argv: Sequence[str] | None = None) -> int:
    """Run the runner ``register`` adds as ``name`` with ``argv`` (default: the process's
    arguments); a :class:`~mover.cli.UsageError` is printed as one line, exit code 2."""
    parser = argparse.ArgumentParser(prog=f"python -m experiments.{name}")
    register(parser.add_subparsers(dest="experiment", required=True))
    args = parser.parse_args([name, *(sys.argv[1:] if argv is None else argv)])
    try:
        return int(args.func(args))
    except UsageError as exc:
        print(f"{parser.prog}: {exc}", file=sys.stderr)
        return 2
