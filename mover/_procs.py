"""Child processes: start one, log its output to a file, stop it; the error for one that ended.

``mover up`` (:mod:`mover._up._supervisor`) and :class:`mover.testing.Cluster` start their
processes here, so both guard against orphans the same way (:func:`~mover._orphans.guarded`:
a child dies with its parent), log the same way and stop the same way: each signal of a ladder
(SIGINT, its clean exit; SIGTERM; SIGKILL) followed by a bounded wait, until all have ended.

A child logs in one of two ways. *Pumped*: its standard output and error share one pipe that
:meth:`Child.pump` copies, line by line, to the log file (and to a callback: ``mover up``
echoes every line). *Direct*: its standard error is the log file itself, written by the child
(nothing lost if this process is killed), and its standard output is a pipe for ready lines.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import os
import signal
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import IO, Self

from ._orphans import guarded

LAST_LINES = 20
"""Lines of a process's output kept for the error when it exits."""
MAX_LINE = 2**20
"""The longest output line read from a pumped process (a longer one is dropped)."""
STOP_LADDER: tuple[tuple[int, float], ...] = (
    (signal.SIGINT, 5.0),
    (signal.SIGTERM, 2.0),
    (signal.SIGKILL, 2.0),
)
"""How :func:`stop` ends processes: each signal, then at most that many seconds' wait."""


class ProcessExited(Exception):
    """A process ended that nobody asked to end: its name, exit code (negative: killed by that
    signal), its last lines of output and its log file (None: it had none).

    ``mover up`` stops the team and prints it as one line; :mod:`mover.testing` reports it
    (:meth:`~mover.testing.Cluster.first_exit`) and its pytest plugin fails the test with it.
    """

    def __init__(
        self, name: str, code: int, last: Sequence[str] = (), log: Path | None = None
    ) -> None:
        self.name, self.code, self.last, self.log = name, code, list(last), log
        how = f"was killed by signal {-code}" if code < 0 else f"exited with code {code}"
        said = self.last[-1] if self.last else "nothing"
        where = f" (its log: {log})" if log is not None else ""
        super().__init__(f"the {name} process {how}; its last word: {said}{where}")

    @property
    def label(self) -> str:
        """The process's name (as :mod:`mover.testing` called it)."""
        return self.name

    @property
    def returncode(self) -> int:
        """The exit code (as :class:`asyncio.subprocess.Process` calls it)."""
        return self.code

    @property
    def tail(self) -> str:
        """The last lines, one text."""
        return "\n".join(self.last)

    @property
    def brief(self) -> str:
        """``NAME exited with code N``: the short form a test report uses."""
        return f"{self.name} exited with code {self.code}"


@dataclass(eq=False)
class Child:
    """One started process: its name, the asyncio process, its log file and last lines.

    ``interruptible`` False makes :func:`stop` send SIGTERM where it would send SIGINT (a
    process still importing prints a traceback on SIGINT, and has nothing to close yet)."""

    name: str
    proc: asyncio.subprocess.Process
    log: Path | None
    group: bool  # its own session: a signal goes to its whole process group
    pumped: IO[bytes] | None = None  # the open log of a pumped child, closed by pump()
    last: collections.deque[str] = field(
        default_factory=lambda: collections.deque(maxlen=LAST_LINES)
    )
    interruptible: bool = True

    def signal(self, sig: int) -> None:
        """Send ``sig`` (to the process group of a child with its own session), unless it ended."""
        if self.proc.returncode is not None:
            return
        with contextlib.suppress(ProcessLookupError, PermissionError):
            if self.group:
                os.killpg(self.proc.pid, sig)
            else:
                self.proc.send_signal(sig)

    async def pump(self, on_line: Callable[[str], None] | None = None) -> int:
        """Copy a pumped child's output to its log, keep its last lines and hand each line to
        ``on_line``, until the output ends; then its exit code."""
        out, log = self.proc.stdout, self.pumped
        assert out is not None and log is not None, "not a pumped child"
        try:
            while True:
                try:
                    raw = await out.readline()
                except ValueError:  # a line longer than MAX_LINE (asyncio drops it)
                    raw = f"(a line over {MAX_LINE} bytes, dropped)\n".encode()
                if not raw:
                    break
                log.write(raw)
                log.flush()
                text = raw.decode(errors="replace").rstrip()
                self.last.append(text)
                if on_line is not None:
                    on_line(text)
            return await self.proc.wait()
        finally:
            log.close()

    def exited(self, code: int) -> ProcessExited:
        """The error for this child having ended with ``code``: its last lines are those
        pumped, else the end of its log file."""
        return ProcessExited(self.name, code, self.last or _tail(self.log), self.log)


async def start(
    name: str,
    argv: Sequence[str],
    *,
    env: dict[str, str],
    log: IO[bytes] | None,
    pump: bool = False,
    stdin: int = asyncio.subprocess.DEVNULL,
    cwd: Path | None = None,
    own_session: bool = False,
) -> Child:
    """Start ``argv`` (guarded: it dies with this process) logging to ``log``, an open file
    that the child takes over (``pump``: through :meth:`Child.pump`; else as its standard
    error, ours closed at once; None: this process's standard error). ``own_session`` puts it
    in a session (process group) of its own, out of reach of the terminal's Ctrl-C. Raises
    OSError when it cannot be started."""
    try:
        proc = await asyncio.create_subprocess_exec(
            *guarded(list(argv)), env=env, cwd=cwd, stdin=stdin,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT if pump else log,
            start_new_session=own_session, limit=MAX_LINE,
        )  # fmt: skip
    except BaseException:
        if log is not None:
            log.close()
        raise
    path = Path(log.name) if log is not None else None
    if log is not None and not pump:
        log.close()  # the child has its own copy
    return Child(name, proc, path, own_session, log if pump else None)


class Processes:
    """A set of processes as an async context: entering starts them (:meth:`_start`), leaving
    stops them (:meth:`aclose`), and a start that fails half-way stops what it started before
    the error goes on, so that nothing is left running. ``mover up``'s supervisor and a team
    across hosts extend it with what they start and how they stop."""

    async def _start(self) -> None:
        """Start the processes (extended)."""
        raise NotImplementedError

    async def aclose(self) -> None:
        """Stop whatever was started (extended; called once the context is left, and after a
        failed start)."""
        raise NotImplementedError

    async def __aenter__(self) -> Self:
        try:
            await self._start()
        except BaseException:
            await self.aclose()
            raise
        return self

    async def __aexit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.aclose()


async def stop(
    children: Sequence[Child], ladder: Sequence[tuple[int, float]] = STOP_LADDER
) -> None:
    """End ``children``: each signal of ``ladder`` to those still running, then a wait of at
    most its seconds for all of them; done once none runs."""
    alive = [c for c in children if c.proc.returncode is None]
    for sig, grace in ladder:
        if not alive:
            return
        for c in alive:
            c.signal(signal.SIGTERM if sig == signal.SIGINT and not c.interruptible else sig)
        waits = [asyncio.ensure_future(c.proc.wait()) for c in alive]
        _, late = await asyncio.wait(waits, timeout=grace)
        for w in late:
            w.cancel()
        alive = [c for c in alive if c.proc.returncode is None]


def _tail(log: Path | None, lines: int = LAST_LINES) -> list[str]:
    if log is None:
        return []
    try:
        return log.read_text(errors="replace").splitlines()[-lines:]
    except OSError:
        return []
