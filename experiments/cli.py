"""`mover experiment NAME ...`: the frame for experiment runners.

Each runner registers itself under the ``mover.experiments`` entry-point group with a
``register(subparsers)`` function that adds its own sub-parser and sets ``func`` (a callable
taking the parsed arguments and returning an exit code).
"""

from __future__ import annotations

import argparse
import logging
from importlib.metadata import entry_points

log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``experiment`` verb and gather the experiment runners under it."""
    parser = sub.add_parser("experiment", help="run a paper's experiment in-process, seeded")
    runners = parser.add_subparsers(dest="experiment", metavar="NAME", required=True)
    for ep in sorted(entry_points(group="mover.experiments"), key=lambda e: e.name):
        try:
            ep.load()(runners)
        except Exception as exc:  # a broken runner must not break the others
            log.debug("experiment %r is unavailable: %s", ep.name, exc)
