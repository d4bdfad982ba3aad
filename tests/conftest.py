"""The quick set is honest: a test whose module is not marked ``processes`` starts no process.

``make check`` runs ``-m "not slow and not processes"`` to give a check of minutes beside the
full suite; that only works if every test that starts a process (a robot, a world, ``mover``
as a command, a pool of workers, a pytest in a subprocess) says so with
``pytestmark = pytest.mark.processes``. This guard makes the marking true by construction: for
an unmarked test, from its fixtures' setup to their teardown, starting a process fails it,
naming the mark to add (and fails the run, should the test's code swallow the error). It
replaces every way a process is born in CPython: ``fork_exec`` (as ``subprocess`` holds it, under
``asyncio``'s too, and as ``multiprocessing`` spawns), ``os.fork`` (and ``forkpty``),
``os.posix_spawn[p]`` and ``os.system``.
"""

from __future__ import annotations

import _posixsubprocess
import contextlib
import os
import subprocess
from collections.abc import Callable, Generator, Iterator
from contextlib import contextmanager

import pytest

# The processes tests start notice a hung member within about a second, as they did before the
# team's patience (10 s by default, for real networks; docs/network-lab.md): the tests of hung
# and stopped members are about what happens once a member is lost, not about waiting for it.
# tests/netlab sets the patience it measures with on the processes it starts.
os.environ.setdefault("MOVER_PATIENCE", "1")


def pytest_configure(config: pytest.Config) -> None:
    """matplotlib builds its font cache on first use by running ``fc-list`` (where fontconfig is
    installed): built here, before any guard, so that whether an unmarked test that plots
    passes does not depend on whether a marked test plotted before it."""
    with contextlib.suppress(ImportError):  # without the plotting extra nothing plots
        import matplotlib.font_manager  # noqa: F401


PROCESSES = "processes"
"""The mark of a module whose tests start processes (declared in pyproject.toml)."""


class ProcessStarted(AssertionError):
    """An unmarked test started a process."""


_STARTED: list[str] = []
"""Each unmarked test that tried, in case its code swallowed the error."""


def _refuse(what: str, test: str) -> Callable[..., object]:
    def refuse(*args: object, **kwargs: object) -> object:
        _STARTED.append(f"{test} ({what})")
        raise ProcessStarted(
            f"{test} starts a process ({what}) but its module is not marked: add "
            f"`pytestmark = pytest.mark.{PROCESSES}` (the quick set, `make check`, leaves "
            "such tests out)"
        )

    return refuse


@contextmanager
def _no_processes(test: str) -> Iterator[None]:
    """While inside, every way to start a process raises :class:`ProcessStarted`."""
    targets: list[tuple[object, str]] = [(_posixsubprocess, "fork_exec")]
    targets += [(subprocess, "_fork_exec")]
    forks = ("fork", "forkpty", "posix_spawn", "posix_spawnp", "system")
    targets += [(os, name) for name in forks if hasattr(os, name)]
    saved = [(owner, name, getattr(owner, name)) for owner, name in targets]
    try:
        for owner, name in targets:
            setattr(owner, name, _refuse(name, test))
        yield
    finally:
        for owner, name, original in saved:
            setattr(owner, name, original)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item) -> Generator[None, object, object]:
    if item.get_closest_marker(PROCESSES) is not None:
        return (yield)
    with _no_processes(item.nodeid):
        return (yield)


def pytest_sessionfinish(session: pytest.Session) -> None:
    if _STARTED:
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if _STARTED:
        terminalreporter.section("tests that start processes but are not marked")
        for line in dict.fromkeys(_STARTED):
            terminalreporter.write_line(line)
