"""The `mover` command's frame.

Verbs are gathered from the ``mover.commands`` entry-point group, as the ``ros2`` command gathers
its verbs, so that this package imports none of the packages that provide them. Each entry point
is a ``register(subparsers)`` function that adds one sub-parser and sets ``func`` — a callable
taking the parsed arguments and returning an exit code. ``python -m mover`` is the same command.

The helpers verbs share (team and logging options, :class:`UsageError`) are public, in
:mod:`mover.cli`.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from importlib.metadata import entry_points
from typing import NoReturn

from .._exceptions import ConfigError
from . import Terminated, UsageError, add_log_arguments, interrupt_on_sigterm, setup_logging

__all__ = ["build_parser", "main"]

log = logging.getLogger("mover.cli")


class _Parser(argparse.ArgumentParser):
    """A parser whose error is one line, naming where to find the usage (argparse prints the
    usage first, several lines). Its sub-parsers are of this class too."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(verb: str | None = None) -> argparse.ArgumentParser:
    """The parser with verb ``verb`` only if it names one that loads (so that ``mover ps``
    imports nothing of the worlds or experiments), else with every verb that loads."""
    parser = _Parser(
        prog="mover", description="Program a team of mobile robots as one distributed program."
    )
    add_log_arguments(parser)
    sub = parser.add_subparsers(dest="verb", metavar="VERB", required=True)
    verbs = sorted(entry_points(group="mover.commands"), key=lambda e: e.name)
    for ep in verbs:
        if ep.name == verb:
            try:
                ep.load()(sub)
                return parser
            except Exception:  # say so below, with the others
                break
    for ep in verbs:
        try:
            ep.load()(sub)
        except Exception as exc:  # one broken verb must not take the others down
            print(f"mover: verb {ep.name!r} is unavailable: {exc}", file=sys.stderr)
    return parser


def _verb_in(argv: Sequence[str]) -> str | None:
    """The verb ``argv`` names: its first word that is not an option or an option's value."""
    words = iter(argv)
    for word in words:
        if word == "--log-level":
            next(words, None)
        elif not word.startswith("-"):
            return word
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mover`` console script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(_verb_in(argv))
    args = parser.parse_args(argv)
    interrupt_on_sigterm()
    try:
        setup_logging(args)
        code = args.func(args)
    except (UsageError, ConfigError) as exc:  # a setting is wrong: one line, no traceback
        print(f"mover {args.verb}: {exc}", file=sys.stderr)
        return 2
    except Terminated:
        return 143
    except KeyboardInterrupt:
        return 130
    return int(code or 0)
