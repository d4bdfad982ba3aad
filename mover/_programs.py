"""Programs: installed coroutines that every member of a team runs, started by name.

A robot process (or a workstation) hosts programs with :class:`ProgramHost`, which exports:

``mover.start(program, run, members, args)``  start a program run here (arguments checked)
``mover.outcome(run)``                        wait for the run to end here; its result or error
``mover.programs()``                          the programs installed here, with signatures

A program is ``async def program(robot, team, **args)``: ``robot`` is whatever the hosting
process gives its programs (its hardware and library), ``team`` the :class:`RunTeam` with the
collectives. Nothing is shipped: the launcher sends a name and data arguments; a process that is
not in the team cannot start anything (every call is authenticated). The launcher is not a
coordinator: it may exit once the run has started, and the run goes on.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import logging
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ._exceptions import BadArguments, MoverError, RobotLost, UnknownProcedure, UnknownRobot
from ._signature import Signature
from ._tasks import Collectives, Policy, TaskTeam, wait_reachable

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.programs")

#: Where members report a run's progress: ``f"{PROGRESS_TOPIC}/{run}"`` carries each
#: :meth:`RunTeam.report` as ``{"member": ..., "phase": ..., **info}``; subscribe to it to watch.
PROGRESS_TOPIC = "mover/run"


class RunTeam(TaskTeam):
    """The team as a program sees it: the collectives, plus progress reports."""

    async def report(self, phase: str, **info: Any) -> None:
        """Tell the launcher (and anyone listening) how this member is doing."""
        await self.node.broadcast(
            f"{PROGRESS_TOPIC}/{self.run}",
            {"member": self.me, "phase": phase, **info},
            reliable=True,
        )


@dataclass
class _Run:
    program: str
    task: asyncio.Task[Any]
    team: RunTeam
    failed: BaseException | None = None  # why the run was ended from outside (fail_all)


class ProgramHost:
    """Hosts installed programs on one node."""

    def __init__(
        self,
        node: Node,
        programs: Mapping[str, Callable[..., Any]],
        robot: Any,
        *,
        policy: Policy = "fail",
        join_timeout: float = 10.0,
        ready: bool = True,
    ) -> None:
        self.node = node
        self.join_timeout = join_timeout
        self.ready = asyncio.Event()  # programs wait for it: set once ``robot`` is usable
        if ready:
            self.ready.set()
        self.robot = robot
        self.programs = dict(programs)
        self.collectives = Collectives(node, policy)
        self._signatures = {name: _args_signature(fn) for name, fn in self.programs.items()}
        self.runs: dict[str, _Run] = {}
        node.export(self.start, "mover.start")
        node.export(self.outcome, "mover.outcome")
        node.export(self.installed, "mover.programs")

    def start(self, program: str, run: str, members: list[str], args: dict[str, Any]) -> None:
        """Start ``program`` as run ``run`` among ``members`` (returns once started)."""
        fn = self.programs.get(program)
        if fn is None:
            raise UnknownProcedure(
                f"no program {program!r} installed on {self.node.name!r} "
                f"(installed: {', '.join(sorted(self.programs)) or 'none'})"
            )
        if run in self.runs:
            raise BadArguments(f"run {run!r} was already started here")
        if self.node.name not in members:
            raise BadArguments(f"{self.node.name!r} is not among the members {members!r}")
        try:
            positional, kwargs = self._signatures[program].bind([], args)
        except TypeError as exc:
            raise BadArguments(f"program {program!r}: {exc}") from None
        team = RunTeam(self.node, run, members, collectives=self.collectives)
        task = asyncio.get_running_loop().create_task(
            self._run(fn, team, positional, kwargs, members)
        )
        task.add_done_callback(_retrieved)  # its outcome is asked for by mover.outcome, if at all
        self.runs[run] = _Run(program, task, team)
        log.info("%s: started %s as run %s among %s", self.node.name, program, run, members)

    async def _run(
        self,
        fn: Callable[..., Any],
        team: RunTeam,
        args: list[Any],
        kwargs: dict[str, Any],
        members: list[str],
    ) -> Any:
        try:
            # Every member starts from the same view of the team (the designated members).
            await self.node.team.wait_for(members, timeout=self.join_timeout)
            async with asyncio.timeout(self.join_timeout):
                await self.ready.wait()
            result = await fn(self.robot, team, *args, **kwargs)
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            # A fault the run could expect (the hardware went away, a member was lost) is one
            # line; a bug in the program keeps its traceback, here and in the outcome.
            log.warning(
                "%s: run %s failed: %s: %s",
                self.node.name,
                team.run,
                type(exc).__name__,
                exc,
                exc_info=None if _expected(exc) else exc,
            )
            with contextlib.suppress(MoverError):  # the node may be closing under it
                await team.report("failed", error=f"{type(exc).__name__}: {exc}")
            raise
        with contextlib.suppress(MoverError):
            await team.report("done")
        return result

    async def outcome(self, run: str) -> dict[str, Any]:
        """Wait for run ``run`` to end here: ``{"result": ...}`` or ``{"error": ...}``."""
        entry = self.runs.get(run)
        if entry is None:
            raise MoverError(f"no run {run!r} on {self.node.name!r}")
        try:
            result = await asyncio.shield(entry.task)
        except asyncio.CancelledError:
            if entry.task.cancelled():
                why = entry.failed
                error = f"{type(why).__name__}: {why}" if why is not None else "cancelled"
                return {"error": error, "steps": _metrics(entry.team)}
            raise
        except Exception as exc:
            outcome = {"error": f"{type(exc).__name__}: {exc}", "steps": _metrics(entry.team)}
            if not _expected(exc):
                outcome["traceback"] = "".join(traceback.format_exception(exc))
            return outcome
        return {"result": result, "steps": _metrics(entry.team)}

    def fail_all(self, reason: BaseException) -> None:
        """End every run under way here with ``reason`` (its ``finally`` blocks run): the
        hardware went away, say. Their outcome is the reason, as an error."""
        for entry in self.runs.values():
            if not entry.task.done():
                entry.failed = reason
                entry.task.cancel()

    async def aclose(self) -> None:
        """End every run under way here (their ``finally`` blocks run) and wait for them."""
        tasks = [entry.task for entry in self.runs.values() if not entry.task.done()]
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    def installed(self) -> dict[str, str]:
        """The installed programs and their arguments."""
        return {name: sig.describe() for name, sig in self._signatures.items()}


def _args_signature(fn: Callable[..., Any]) -> Signature:
    """The signature of a program's data arguments (all but ``robot`` and ``team``)."""
    sig = Signature(fn)
    params = list(sig.signature.parameters.values())[2:]
    sig.signature = sig.signature.replace(parameters=params)
    if not inspect.iscoroutinefunction(fn):
        raise TypeError(f"program {fn.__name__!r} must be an async function")
    return sig


async def launch(
    node: Node,
    program: str,
    members: list[str],
    args: dict[str, Any],
    *,
    run: str,
    wait: bool = True,
) -> dict[str, dict[str, Any]]:
    """Start ``program`` on every one of ``members``; with ``wait``, return each one's outcome.

    Raises the first CallError of a start that fails (unknown program, bad arguments, refused).
    """
    await asyncio.gather(
        *(node.call(m, "mover.start", program, run, members, args, timeout=10) for m in members)
    )
    if not wait:
        return {}

    async def outcome(member: str) -> dict[str, Any]:
        while True:
            try:
                result: dict[str, Any] = await node.call(member, "mover.outcome", run, timeout=None)
                return result
            except (RobotLost, UnknownRobot) as exc:
                if not await wait_reachable(node, member):
                    return {"error": f"{type(exc).__name__}: {exc}"}
            except MoverError as exc:
                return {"error": f"{type(exc).__name__}: {exc}"}

    outcomes = await asyncio.gather(*(outcome(m) for m in members))
    return dict(zip(members, outcomes, strict=True))


def _metrics(team: TaskTeam) -> list[dict[str, Any]]:
    return [{"step": m.step, "kind": m.kind, "messages": m.messages} for m in team.metrics]


def _expected(exc: BaseException) -> bool:
    """Whether a run's failure is a fault it could expect (mover's errors, or an exception
    whose class says ``expected = True``, as a lost hardware's does), not a bug."""
    return isinstance(exc, MoverError) or bool(getattr(exc, "expected", False))


def _retrieved(task: asyncio.Task[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieved: a failed run nobody asked about is not an error at exit
