"""The public toolkit of mover's command lines: what every process's CLI shares.

The verbs of ``mover`` and the robot process (``python -m robots``) take the same team options,
and every process the same logging options; defining them here once keeps their spelling and
meaning the same everywhere (they were written twice before, and the log level was set two
ways). Nothing here opens a session or reads the environment until it is called:

* :func:`add_team_arguments` — ``--team NAME`` (default ``$MOVER_TEAM``; the key comes from
  ``$MOVER_TEAM_KEY`` or ``$MOVER_TEAM_KEY_FILE``) and ``--connect ENDPOINT`` (repeatable), and
  :func:`team_from_args` to turn them into a :class:`~mover.TeamCredentials` and a
  :class:`~mover.NodeConfig`;
* :func:`add_log_arguments` and :func:`setup_logging` — ``-v/--verbose`` (``-v`` INFO, ``-vv``
  DEBUG) and ``--log-level LEVEL``; with neither, ``$MOVER_LOG_LEVEL`` (``LOG_LEVEL_ENV``),
  else the process's default;
* :func:`bounded` — the argparse type of every number with bounds (:func:`positive` and
  :func:`seed`, from 0 to ``MAX_SEED``, are two of them);
* :func:`add_command` — a sub-command that runs a function, the function's docstring its
  description (one copy of the text);
* :class:`UsageError` — a command-line mistake, which a command prints as one line and exits 2.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import signal
import typing

from .._config import NodeConfig, TeamCredentials
from .._keys import check_name as _check_name
from .._orphans import guarded

if typing.TYPE_CHECKING:
    from collections.abc import Callable

_N = typing.TypeVar("_N", int, float)

__all__ = [
    "LOG_LEVEL_ENV",
    "MAX_SEED",
    "Terminated",
    "UsageError",
    "add_command",
    "add_log_arguments",
    "add_team_arguments",
    "bounded",
    "guarded",
    "interrupt_on_sigterm",
    "json_argument",
    "json_object",
    "member_name",
    "positive",
    "seed",
    "setup_logging",
    "team_from_args",
]


class Terminated(KeyboardInterrupt):
    """The process was sent SIGTERM: it ends as on Ctrl-C (its ``finally`` blocks run)."""


def interrupt_on_sigterm() -> None:
    """Make SIGTERM end this process the way Ctrl-C does (:class:`Terminated`, a
    ``KeyboardInterrupt``): asyncio cancels the main task, every ``finally`` runs, and the
    command exits with one line at most and status 143. A handler set already is kept."""
    if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        return

    def terminated(signum: int, frame: typing.Any) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second SIGTERM ends it at once
        raise Terminated()

    signal.signal(signal.SIGTERM, terminated)


def json_argument(text: str, what: str) -> typing.Any:
    """The JSON value of a command-line argument ``what``, else a one-line UsageError."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise UsageError(
            f"{what} is not JSON ({exc.msg}): {text!r}; quote strings as '\"text\"'"
        ) from None
    except RecursionError:
        raise UsageError(f"{what} is not JSON: nested too deeply") from None


def json_object(text: str, what: str) -> dict[str, typing.Any]:
    """The JSON object of a command-line argument ``what``, else a one-line UsageError."""
    value = json_argument(text, what)
    if not isinstance(value, dict):
        raise UsageError(f"{what} must be a JSON object, got {type(value).__name__}")
    return value


def bounded(
    kind: type[_N], low: _N | None = None, high: _N | None = None, *, above: bool = False
) -> Callable[[str], _N]:
    """An argparse type: a whole number (``int``) or a finite number (``float``) from ``low``
    to ``high`` (either may be None: no bound; ``above``: ``low`` itself excluded), else a
    one-line error such as ``must be from 0 to 1000, got 5000``. The one number type of every
    command line, so that every bound is checked and told the same way."""
    words = []
    if low is not None and high is not None and not above:
        words.append(f"from {_num(low)} to {_num(high)}")
    else:
        if low is not None:
            words.append(f"{'above' if above else 'at least'} {_num(low)}")
        if high is not None:
            words.append(f"at most {_num(high)}")
    noun = "" if kind is int else "a number " if high is not None else "a finite number "
    wanted = f"must be {noun}{' and '.join(words)}".rstrip()

    def parse(text: str) -> _N:
        try:
            value = kind(text)
        except ValueError:
            what = "a whole number" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"not {what}: {text!r}") from None
        fits = kind is int or math.isfinite(value)  # NaN, inf: never a bounded float
        fits = fits and (low is None or (value > low if above else value >= low))
        if not (fits and (high is None or value <= high)):
            raise argparse.ArgumentTypeError(f"{wanted}, got {text}")
        return value

    parse.__doc__ = f"An argparse type: a number that {wanted}."
    return parse


def _num(value: float) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


#: An argparse type: a finite number above zero (seconds, speeds), else a one-line error.
positive = bounded(float, 0.0, above=True)

#: The largest seed a command line takes (seeds are 0 to ``MAX_SEED``).
MAX_SEED = 2**63 - 1

#: An argparse type: a seed, from 0 to :data:`MAX_SEED`.
seed = bounded(int, 0, MAX_SEED)


def member_name(text: str) -> str:
    """An argparse type: a valid member (robot, world, tool) name, else a one-line error."""
    try:
        return _check_name("member", text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


#: The environment variable that sets the log level of a process given no logging option.
LOG_LEVEL_ENV = "MOVER_LOG_LEVEL"

_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL")
_FORMAT = "%(asctime)s %(name)s %(levelname)s %(message)s"


class UsageError(Exception):
    """A command-line mistake: printed as one line, exit code 2."""


def add_command(
    sub: argparse._SubParsersAction[argparse.ArgumentParser],
    name: str,
    run: Callable[[argparse.Namespace], int],
    help: str,
    description: str | None = None,
) -> argparse.ArgumentParser:
    """Add ``name`` to the sub-parsers ``sub``: it calls ``run(args)``; ``help`` is its line in
    the parent's list, and ``description`` (by default ``run``'s docstring) what its ``--help``
    prints."""
    p = sub.add_parser(name, help=help, description=description or run.__doc__)
    p.set_defaults(func=run)
    return p


def add_team_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--team NAME`` and ``--connect ENDPOINT`` (repeatable) to ``parser``.

    Both are None when not given: :func:`team_from_args` then reads ``$MOVER_TEAM`` and
    ``$MOVER_CONNECT`` (see :meth:`mover.TeamCredentials.from_env`,
    :meth:`mover.NodeConfig.from_env`).
    """
    parser.add_argument(
        "--team",
        help="team name (default: $MOVER_TEAM); the key comes from "
        "$MOVER_TEAM_KEY or $MOVER_TEAM_KEY_FILE",
    )
    parser.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help="zenoh endpoint of a team member or router; repeatable",
    )


def team_from_args(args: argparse.Namespace) -> tuple[TeamCredentials, NodeConfig]:
    """The team and node settings of :func:`add_team_arguments`' options and the environment.

    Raises :class:`UsageError` (one line) when the team, its key or an endpoint is wrong.
    """
    try:
        return TeamCredentials.from_env(args.team), NodeConfig.from_env(args.connect or ())
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _level(text: str) -> str:
    name = text.strip().upper()
    if name not in _LEVELS:
        raise ValueError(f"unknown log level {text!r} (one of {', '.join(_LEVELS)})")
    return name


def _level_argument(text: str) -> str:
    try:
        return _level(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_log_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``-v/--verbose`` (counted) and ``--log-level LEVEL`` to ``parser``."""
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help=f"more log lines: -v INFO, -vv DEBUG (default: ${LOG_LEVEL_ENV})",
    )
    parser.add_argument(
        "--log-level",
        type=_level_argument,
        metavar="LEVEL",
        help=f"{', '.join(_LEVELS)} (default: ${LOG_LEVEL_ENV}); wins over -v",
    )


def setup_logging(args: argparse.Namespace, *, default: str = "WARNING") -> int:
    """Configure the root logger from :func:`add_log_arguments`' options; return the level.

    ``--log-level`` wins, then ``-v`` (INFO) or ``-vv`` (DEBUG), then ``$MOVER_LOG_LEVEL``,
    then ``default``. Raises :class:`UsageError` when ``$MOVER_LOG_LEVEL`` names no level. As
    :func:`logging.basicConfig`, it leaves a root logger that already has handlers alone.
    """
    if args.log_level:
        name = str(args.log_level)
    elif args.verbose:
        name = "INFO" if args.verbose == 1 else "DEBUG"
    else:
        try:
            name = _level(os.environ.get(LOG_LEVEL_ENV) or default)
        except ValueError as exc:
            raise UsageError(f"${LOG_LEVEL_ENV}: {exc}") from None
    level: int = getattr(logging, name)
    logging.basicConfig(level=level, format=_FORMAT)
    return level
