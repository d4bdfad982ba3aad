"""Programs: installed coroutines that every member of a team runs, started by name.

A robot process (or a workstation) hosts programs with :class:`ProgramHost`, which exports:

``mover.start(program, run, members, args, seed=None, share=False)``
                                              start a program run here (arguments checked)
``mover.outcome(run)``                        wait for the run to end here; its result or error
``mover.status()``                            the runs here (the last ``HISTORY``), phase and state
``mover.cancel(run, by="")``                  end a run here (its ``finally`` blocks run)
``mover.programs()``                          the programs installed here, with signatures

A program is ``async def program(robot, team, **args)``: ``robot`` is whatever the hosting
process gives its programs (its hardware and library), ``team`` the :class:`RunTeam` with the
collectives. Nothing is shipped: the launcher sends a name and data arguments; a process that is
not in the team cannot start anything (every call is authenticated). The launcher is not a
coordinator: it may exit once the run has started, and the run goes on.

A host runs one run at a time: a second is refused (``Refused``, naming the run under way)
unless both were started with ``share=True``. A run starts, once its members are seen and the
hardware is ready, by engaging the host's clock (``ProgramHost.clock``, a
:class:`~mover.RunClock`, if the hardware has one: a lock-step world then waits for this robot)
and passing the team's begin barrier (:meth:`~mover.RunTeam.begin`: every member starts on
the same tick); the clock is released when the last run here ends, however it ends. A member
that was out of the team's reach past its lease (stopped, cut off) while the others went on
without it finds its run ended (``MemberLost``) as soon as it sees them again: it is not left
busy in a run nobody else is in.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import logging
import time
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ._collective import (
    POLICIES,
    RUN_LOST,
    SEED_LIMIT,
    Collectives,
    Policy,
    RunClock,
    TaskTeam,
    wait_reachable,
)
from ._exceptions import (
    BadArguments,
    CallError,
    ExpectedFault,
    MemberLost,
    MoverError,
    Refused,
    RobotLost,
    UnknownProcedure,
    UnknownRobot,
)
from ._futures import failure
from ._signature import Signature

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.programs")

#: Where members report a run's progress: ``f"{PROGRESS_TOPIC}/{run}"`` carries each
#: :meth:`RunTeam.report` as ``{"member": ..., "phase": ..., **info}``; subscribe to it to watch.
PROGRESS_TOPIC = "mover/run"
HISTORY = 32  # runs a host remembers (for mover.status and mover.outcome), the running ones too
CANCEL_WAIT = 10.0  # seconds mover.cancel waits for a run's finally blocks


class RunTeam(TaskTeam):
    """The team as a program sees it: the collectives, plus progress reports."""

    phase: str = "starting"  # the last phase this member reported (mover.status shows it)
    info: dict[str, Any]

    async def report(self, phase: str, **info: Any) -> None:
        """Tell the launcher (and anyone listening) how this member is doing. In simulated time
        the report carries this member's clock as ``t`` (unless ``info`` has one), so that a
        watcher can time phases without racing the world's snapshots."""
        self.phase, self.info = phase, info
        timed = {"t": self.clock.now()} if self.clock is not None and self.simulated else {}
        await self.node.broadcast(
            f"{PROGRESS_TOPIC}/{self.run}",
            {"member": self.me, "phase": phase, **info, **({} if "t" in info else timed)},
            reliable=True,
        )


@dataclass
class _Run:
    program: str
    task: asyncio.Task[Any]
    team: RunTeam
    share: bool = False
    started: float = field(default_factory=time.time)
    failed: BaseException | None = None  # why the run was ended from outside (fail_all)
    cancelled_by: str | None = None  # who ended it with mover.cancel

    @property
    def state(self) -> str:
        """running, done, failed or cancelled."""
        if not self.task.done():
            return "running"
        if self.task.cancelled():
            return "failed" if self.failed is not None else "cancelled"
        return "failed" if failure(self.task) is not None else "done"

    def status(self) -> dict[str, Any]:
        """What mover.status says of this run."""
        return {
            "run": self.team.run,
            "program": self.program,
            "members": self.team.members,
            "phase": self.team.phase,
            "info": getattr(self.team, "info", {}),
            "started": self.started,
            "state": self.state,
            "seed": self.team.seed,
            "share": self.share,
        }


class ProgramHost:
    """Hosts installed programs on one node."""

    def __init__(
        self,
        node: Node,
        programs: Mapping[str, Callable[..., Any]],
        robot: object,
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
        #: The hardware's clock for reproducible runs (None: no hardware, or none yet); the
        #: robot process sets it when the hardware connects.
        self.clock: RunClock | None = None
        self.programs = programs  # not copied: a lazy mapping loads a program when it is asked
        self.collectives = Collectives(node, policy)
        self._signatures: dict[str, Signature] = {}
        self.runs: dict[str, _Run] = {}  # the last HISTORY runs, oldest first
        self._engaged: RunClock | None = None  # the clock the runs here engaged
        self._engaging = asyncio.Lock()
        node.export(self.start, "mover.start")
        node.export(self.outcome, "mover.outcome")
        node.export(self.status, "mover.status")
        node.export(self.cancel, "mover.cancel")
        node.export(self.installed, "mover.programs")

    def start(
        self,
        program: str,
        run: str,
        members: list[str],
        args: dict[str, Any],
        seed: int | None = None,
        share: bool = False,
        policy: str = "fail",
    ) -> None:
        """Start ``program`` as run ``run`` among ``members`` (returns once started).

        ``seed`` seeds the team's random choices (:meth:`TaskTeam.rng`; default: derived from
        ``run``). A host busy in a run refuses another unless both are started with ``share``.
        ``policy`` says what a member lost in a step does to it: ``fail`` it (MemberLost), or
        let the ``survivors`` go on without it.
        """
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
        if seed is not None and not 0 <= seed < SEED_LIMIT:
            raise BadArguments(f"seed must be at least 0 and below 2**63, got {seed}")
        if policy not in POLICIES:
            raise BadArguments(f"policy must be one of {', '.join(POLICIES)}, got {policy!r}")
        busy = [e for e in self.runs.values() if not e.task.done()]
        if busy and not (share and all(e.share for e in busy)):
            other = busy[0]
            hint = (
                "cancel it first (mover cancel), or start both with share=True "
                "(mover run --share) to run them side by side"
            )
            raise Refused(
                f"{self.node.name!r} is busy in run {other.team.run!r} ({other.program}, "
                f"running for {time.time() - other.started:.0f} s): {hint}"
            )
        if len(busy) >= HISTORY:
            raise Refused(f"{self.node.name!r} has {len(busy)} runs under way: no more")
        try:
            positional, kwargs = self._signature(program).bind([], args)
        except TypeError as exc:
            raise BadArguments(f"program {program!r}: {exc}") from None
        self.collectives.set_policy(run, policy)
        team = RunTeam(self.node, run, members, collectives=self.collectives, seed=seed)
        team.info = {}
        task = asyncio.get_running_loop().create_task(
            self._run(fn, team, positional, kwargs, members)
        )
        task.add_done_callback(failure)  # its outcome is asked for by mover.outcome, if at all
        task.add_done_callback(lambda _: self.collectives.end_run(run))
        self.runs[run] = _Run(program, task, team, share=share)
        while len(self.runs) > HISTORY:  # the oldest finished run goes (running ones stay)
            old = next((r for r, e in self.runs.items() if e.task.done()), None)
            if old is None:
                break
            del self.runs[old]
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
            await self.node.membership.wait_for(members, timeout=self.join_timeout)
            async with asyncio.timeout(self.join_timeout):
                await self.ready.wait()
            team.clock = await self._engage()
            await team.begin(timeout=self.join_timeout)  # every member starts on the same tick
            team.phase = "running"
            result = await self._program(fn, team, args, kwargs)
        except asyncio.CancelledError:
            entry = self.runs.get(team.run)
            if entry is not None and entry.cancelled_by is not None:
                with contextlib.suppress(MoverError):  # the node may be closing under it
                    await team.report("cancelled", by=entry.cancelled_by)
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
        finally:
            self._release(team.run)
        with contextlib.suppress(MoverError):
            await team.report("done")
        return result

    async def _program(
        self, fn: Callable[..., Any], team: RunTeam, args: list[Any], kwargs: dict[str, Any]
    ) -> Any:
        """The program, beside the watch for the end of a stall (a TaskGroup of two); what the
        program raises is raised as itself (unwrapped from the group, its context untouched)."""
        failed: BaseException | None = None
        try:
            async with asyncio.TaskGroup() as tasks:
                watch = tasks.create_task(self._watch_dropped(team))
                try:
                    result = await fn(self.robot, team, *args, **kwargs)
                finally:
                    watch.cancel()
        except BaseExceptionGroup as group:  # the program's error, or the watch's MemberLost
            failed = group.exceptions[0] if len(group.exceptions) == 1 else group
        if failed is not None:
            raise failed  # (outside the handler: the error's own context stays)
        return result

    async def _watch_dropped(self, team: RunTeam) -> None:
        """Raise MemberLost if the team went on without this member while it was out of reach
        (stopped past its lease, or cut off): a member of the run that comes back into view
        (after it, or this member, was gone) is asked what run steps it knows of that lost or
        left out members (one call per return; nothing while the team stays whole)."""
        others = set(team.members) - {team.me}
        left: set[str] = set()
        async for event in self.node.membership.events():
            if event.name not in others:
                continue
            if event.kind == "leave":
                left.add(event.name)
                continue
            if event.name not in left:
                continue
            left.discard(event.name)
            try:
                said = await self.node.call(event.name, RUN_LOST, team.run, timeout=5)
            except MoverError:
                continue  # gone again, or an older member: the steps will tell
            lost = {m for m in said if isinstance(m, str)} if isinstance(said, list) else set()
            if team.me in lost:
                raise MemberLost(
                    f"run {team.run!r} went on without this member ({team.me}): it was out "
                    f"of the team's reach past its lease; {event.name} counts {sorted(lost)} lost",
                    members=frozenset(lost),
                )
            if lost and self.collectives.policy_of(team.run) == "fail":
                raise MemberLost(
                    f"run {team.run!r} lost {sorted(lost)} while this member ({team.me}) was "
                    f"out of the team's reach (as {event.name} knows it)",
                    members=frozenset(lost),
                )

    async def _engage(self) -> RunClock | None:
        """Engage the hardware's clock for a run (once for runs that share it)."""
        async with self._engaging:
            clock = self.clock
            if clock is not None and clock is not self._engaged:
                await clock.engage()
                self._engaged = clock
            return clock

    def _release(self, ending: str) -> None:
        """Run ``ending`` ends: release the clock if no other run here is under way."""
        others = [e for r, e in self.runs.items() if r != ending and not e.task.done()]
        if not others and self._engaged is not None:
            clock, self._engaged = self._engaged, None
            try:
                clock.release()
            except Exception as exc:  # the hardware may be gone: the next run engages anew
                log.warning("%s: releasing the clock failed: %s", self.node.name, exc)

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
                if why is not None:
                    error = f"{type(why).__name__}: {why}"
                elif entry.cancelled_by is not None:
                    error = f"cancelled by {entry.cancelled_by}"
                else:
                    error = "cancelled"
                return {"error": error, "steps": _metrics(entry.team)}
            raise
        except Exception as exc:
            outcome = {"error": f"{type(exc).__name__}: {exc}", "steps": _metrics(entry.team)}
            if not _expected(exc):
                outcome["traceback"] = "".join(traceback.format_exception(exc))
            return outcome
        return {"result": result, "steps": _metrics(entry.team)}

    def status(self) -> list[dict[str, Any]]:
        """The runs here, oldest first (the last ``HISTORY``): run, program, members, phase and
        info of this member's last report, started (seconds since the epoch), state (running,
        done, failed, cancelled), seed, share."""
        return [entry.status() for entry in self.runs.values()]

    async def cancel(self, run: str, by: str = "") -> dict[str, Any]:
        """End run ``run`` here (its ``finally`` blocks run) and return its outcome; ``by``
        names who asked (the outcome's error says ``cancelled by ...``). A run that has
        already ended keeps its outcome."""
        entry = self.runs.get(run)
        if entry is None:
            raise MoverError(f"no run {run!r} on {self.node.name!r}")
        if not entry.task.done():
            entry.cancelled_by = by or "a team member"
            entry.task.cancel()
            log.warning("%s: run %s cancelled by %s", self.node.name, run, entry.cancelled_by)
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(CANCEL_WAIT):
                    await asyncio.wait({entry.task})
        if not entry.task.done():
            return {"error": f"still ending after {CANCEL_WAIT} s (its finally blocks run)"}
        return await self.outcome(run)

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
        out = {}
        for name in self.programs:
            with contextlib.suppress(KeyError):  # a program that does not load is left out
                out[name] = self._signature(name).describe()
        return out

    def _signature(self, name: str) -> Signature:
        sig = self._signatures.get(name)
        if sig is None:
            sig = self._signatures[name] = _args_signature(self.programs[name])
        return sig


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
    seed: int | None = None,
    share: bool = False,
    policy: Policy = "fail",
) -> dict[str, dict[str, Any]]:
    """Start ``program`` on every one of ``members``; with ``wait``, return each one's outcome.

    ``seed`` seeds the run's random choices (default: derived from ``run``); ``share`` lets it
    run beside runs under way that were started with ``share`` too; ``policy`` is what a member
    lost during a step does: ``fail`` the step (MemberLost) or leave the ``survivors`` to go on
    without it (its result missing from an AND's). Raises the first CallError
    of a start that fails (unknown program, bad arguments, refused: a member busy in another
    run); the members that did start are then cancelled.
    """
    starts = await asyncio.gather(
        *(
            node.call(
                m, "mover.start", program, run, members, args, seed, share, policy, timeout=10
            )
            for m in members
        ),
        return_exceptions=True,
    )
    failed = [e for e in starts if isinstance(e, BaseException)]
    if failed:
        started = [m for m, e in zip(members, starts, strict=True) if e is None]
        await asyncio.gather(
            *(node.call(m, "mover.cancel", run, node.name, timeout=15) for m in started),
            return_exceptions=True,
        )
        first = next((e for e in failed if isinstance(e, CallError)), failed[0])
        raise first
    if not wait:
        return {}
    return await outcomes(node, run, members)


async def outcomes(node: Node, run: str, members: list[str]) -> dict[str, dict[str, Any]]:
    """Wait for run ``run`` to end on every one of ``members``: each one's outcome (a member
    that is lost for good gives an error)."""

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

    ends = await asyncio.gather(*(outcome(m) for m in members))
    return dict(zip(members, ends, strict=True))


def _metrics(team: TaskTeam) -> list[dict[str, Any]]:
    return [{"step": m.step, "kind": m.kind, "messages": m.messages} for m in team.metrics]


def _expected(exc: BaseException) -> bool:
    """Whether a run's failure is a fault it could expect (mover's errors, or an
    :class:`~mover.ExpectedFault`, as a lost hardware is), not a bug."""
    return isinstance(exc, (MoverError, ExpectedFault))
