"""Cooperative steps among team members: ``distributed_or`` and ``distributed_and``.

Every member of a program run calls the same collectives in the same order, so the n-th
collective of a run is the same step on every member. Each step has a designated member, chosen
as the task runs: the first (by name) of the step's members that is alive. It is an ordinary
member, not a server; if it dies, the next one takes over.

OR (MOVER's ``distributed_or``). Every member starts the operation. The first member to finish
claims the win from the designated member, which takes the first claim it receives — one place,
one order, so all members agree on one winner even when several finish within the same
millisecond — and answers the claim. A member that has not heard the decision within
``POLL_AFTER`` (a long step) asks the designated member for it and waits on that call, which
also tells it when the designated member is lost. Members that did not ask get the decision in
one broadcast. The others' operations are then cancelled (their ``finally`` blocks run: motors
stop). Messages per step: n+1 for a short step (a claim, its answer, n-1 deliveries of the
announcement), 2n for a long one (n-1 questions and answers, the claim and its answer).

OR in simulated time (the team has a :class:`RunClock`, every member of the run has one: see
:meth:`TaskTeam.begin`). A lock-step world's time is the same on every member, and the first to
finish in that time should win, whatever order the claims arrive in. A claim carries its finish
time (``clock.now()`` as the operation returned). The designated member then asks each live
member that has not claimed, ``mover.or_passed(run, step, t)`` with ``t`` the earliest claimed
time, for proof that it went past ``t``: the member answers once its operation for the step
finished (with its finish time: its claim is on its way), or its clock passed ``t``
(``clock.passed``), or at once if its operation failed or the run ended here (it will never
claim); a member that has not reached the step yet answers once it has. The designated member
decides when every live member has claimed or shown it went past the earliest claimed time:
the winner is the earliest finish time, ties going to the first member by name. A member that
leaves meanwhile is handled as in any step (``MemberLost``, or survived). The decision reaches
the members as above. Messages: 3(n - 1) for a short step (a claim and its answer, n - 2
questions and their answers — the designated member asks itself for free — and n - 1
deliveries of the announcement; the same when the designated member wins: n - 1 questions, no
claim sent), at most 4(n - 1) for a long one (polls replace the announcement); each further
claim before the decision adds two. Without a clock the wall-clock rule above holds, at its cost.
A member that went past the earliest claimed time is held there (``RunClock.hold``: it hands in
no command on later readings) until it knows the decision, and its operation is cancelled
before it is released: in a lock-step world the losers stop on the same tick, whatever the
wall clock does. AND in simulated time: a member that finished is idle while it waits
(``RunClock.waiting``: the world neither waits for it nor moves on because of it), and a
``rejoin`` step (2(n - 1) messages) engages every member again before any goes on; so when
the last one finishes the world holds still until all have been told. A run then repeats to
the last digit.

Beginning (:meth:`TaskTeam.begin`, step 0, of kind ``"begin"``, which every run hosted by
:class:`~mover.ProgramHost` starts with): an AND barrier in which each member reports its
clock's time, so that all start on the same tick; the members learn whether every one of them
has a clock (then their ORs are decided in simulated time), and a spread of start times is
logged as a warning. Cost: 2(n - 1) messages.

Randomness: :attr:`TaskTeam.seed` (given at launch, else derived from the run's name) and
:meth:`TaskTeam.rng`, one generator per (seed, member, stream), so that the same seed gives the
same choices on every run whatever the run is called.

AND, designated variant (section 4.4): each member sends its result to the designated member and
gets everybody's results in the reply, once all have finished: 2(n-1) messages.
AND, all-to-all: each member sends its result to every other member: 2n(n-1) messages.
(A message is one sealed envelope; a call is a request and its reply.)

Failures. A member that leaves the team during a step (its process died or hung past its lease)
makes the step fail with :class:`MemberLost` within about a second, or, with
``policy="survivors"``, the step goes on without it (an OR whose members all died still fails).
A member that has lost every link (the network is gone) does not count anyone as lost: the step
stalls, and resumes when the links return, re-sending what was not answered; the designated
member keeps its state, so no result is lost. Limitation: if the membership views of two members
disagree for a moment (a link flapping), both may act as designated member of the same step;
taking over waits until every live member has re-joined, which covers the common case.

Modules: this one is a member's side (:class:`TaskTeam`); the designated member's side is
:mod:`mover._collectives` (:class:`Collectives`), and what both share (the decision, the
step's state, the constants) is :mod:`mover._steps`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import random
import time
from collections.abc import Awaitable, Callable, Sequence
from typing import TYPE_CHECKING, Any

from ._collectives import Collectives
from ._exceptions import (
    MemberLost,
    NotDelivered,
)
from ._steps import (
    _STEP_MEMORY,
    CALL_TIMEOUT,
    DECIDED_TOPIC,
    LOST_GRACE,
    POLL_AFTER,
    SEED_LIMIT,
    Decision,
    OperationFailed,
    Outcome,
    Policy,
    RunClock,
    Settled,
    StepMetrics,
    _LocalOp,
    _Retry,
    _StepTasks,
    _unwire,
    seed_of,
    wait_reachable,
)

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.tasks")

__all__ = [
    "CALL_TIMEOUT",
    "DECIDED_TOPIC",
    "LOST_GRACE",
    "POLL_AFTER",
    "SEED_LIMIT",
    "_STEP_MEMORY",
    "Collectives",
    "Decision",
    "OperationFailed",
    "Outcome",
    "Policy",
    "RunClock",
    "StepMetrics",
    "TaskTeam",
    "seed_of",
    "wait_reachable",
]


# -- a member's side ------------------------------------------------------------------------------


class TaskTeam:
    """The members of one program run, and the collective steps among them.

    ``members`` must be the same list on every member; ``run`` names the run (the same on every
    member). ``stall_timeout`` bounds how long a step waits for lost links to come back.
    A node serves collectives through one :class:`Collectives` (it exports fixed procedure
    names): when a node takes part in several runs, pass the same ``collectives`` to each
    (``ProgramHost`` does); without it, a new one is made and replaces the previous one.

    ``clock`` (a :class:`RunClock`, or None) makes ORs decided in simulated time when every
    member has one (see :meth:`begin`; a team that never begins trusts its own clock).
    ``seed`` (0 <= seed < 2**63; default: derived from ``run``) seeds :meth:`rng`.
    """

    def __init__(
        self,
        node: Node,
        run: str,
        members: Sequence[str],
        *,
        collectives: Collectives | None = None,
        policy: Policy = "fail",
        stall_timeout: float = 60.0,
        clock: RunClock | None = None,
        seed: int | None = None,
    ) -> None:
        if node.name not in members:
            raise ValueError(f"{node.name!r} is not one of the members {list(members)!r}")
        if seed is not None and not 0 <= seed < SEED_LIMIT:
            raise ValueError(f"seed must be at least 0 and below 2**63, got {seed}")
        self.node = node
        self.run = run
        self.clock = clock
        self.seed = seed_of(run) if seed is None else seed
        self._timed: bool | None = None  # whether every member has a clock (known at begin)
        self.members = sorted(set(members))
        self.collectives = collectives or Collectives(node, policy)
        if isinstance(self.collectives, Collectives):
            self.collectives.start_run(run)
        self.stall_timeout = stall_timeout
        self.metrics: list[StepMetrics] = []
        self._step = 0

    @property
    def me(self) -> str:
        """This member's name."""
        return self.node.name

    def rng(self, stream: str = "") -> random.Random:
        """A generator for this member's random choices, seeded from (``seed``, this member's
        name, ``stream``): the same seed gives the same choices on every run, whatever the run
        is called, and each member and stream its own sequence. Each call starts afresh."""
        return random.Random(f"{self.seed}/{self.me}/{stream}")

    @property
    def simulated(self) -> bool:
        """Whether this team's ORs are decided in simulated time (see :meth:`begin`)."""
        return self.clock is not None and self._timed is not False

    async def begin(self, timeout: float | None = None) -> None:
        """The barrier a run starts with (step 0, of kind ``"begin"``): every member reports
        its clock's time and goes on once all have, so that all start on the same tick.

        From then on the team's ORs are decided in simulated time if every member has a clock,
        by wall-clock arrival if any has none. Members whose clocks differ are logged (a
        warning naming the spread). Raises MemberLost if a member is lost, or if not every
        member began within ``timeout`` seconds.
        """
        if self._step != 0 or any(m.kind == "begin" for m in self.metrics):
            raise RuntimeError("begin() is a run's first step, and only one")
        metrics = StepMetrics(0, "begin")  # step 0: the program's own steps count from 1
        self.metrics.append(metrics)
        now = self.clock.now() if self.clock is not None else None
        try:
            async with asyncio.timeout(timeout):
                decision = await self._and_designated(metrics, {"now": now})
        except TimeoutError:
            raise MemberLost(
                f"run {self.run!r}: not every member of {self.members} began within {timeout} s",
                members=frozenset(self.members) - {self.me},
            ) from None
        metrics.continued = time.perf_counter()
        self._raise_lost(metrics, decision)
        nows: dict[str, float | None] = {}
        for member, report in decision.results.items():
            value = report.get("now") if isinstance(report, dict) else None
            nows[member] = float(value) if isinstance(value, (int, float)) else None
        timed = {m: v for m, v in nows.items() if v is not None}
        self._timed = len(timed) == len(nows)
        if self._timed and timed and max(timed.values()) > min(timed.values()):
            spread = max(timed.values()) - min(timed.values())
            log.warning(
                "%s: run %r began %.3f s of simulated time apart: %s",
                self.me,
                self.run,
                spread,
                ", ".join(f"{m} {v:.3f}" for m, v in sorted(timed.items())),
            )
        elif timed and not self._timed:
            log.info(
                "%s: run %r: %s have no clock; its ORs go by wall-clock arrival",
                self.me,
                self.run,
                sorted(m for m, v in nows.items() if v is None),
            )

    def _raise_lost(self, metrics: StepMetrics, decision: Decision) -> None:
        if decision.kind == "lost":
            raise MemberLost(
                decision.lost_message(self.run, metrics.step, self.me),
                members=frozenset(decision.lost),
            )

    async def distributed_or(
        self,
        operation: Callable[[], Awaitable[Any]],
        continuation: Callable[[Outcome], Awaitable[Any]] | None = None,
    ) -> Any:
        """Run ``operation`` on every member; the first to finish wins, the others stop.

        Returns the :class:`Outcome` (winner and its result), or what ``continuation(outcome)``
        returns. Raises MemberLost if a member is lost (policy ``fail``) or all are.
        """
        metrics = self._begin("or")
        async with _StepTasks() as tasks:  # leaving it awaits the losers' cleanup
            clock = self.clock if self.simulated else None
            local = _LocalOp(clock, operation, tasks.start) if clock is not None else None
            op = local.op if local is not None else tasks.start(operation())
            self.collectives.reached(self.run, metrics.step, local)
            try:
                decision = await self._or_decision(metrics, tasks, op, local)
            finally:
                tasks.cancel()  # the losers' operations, a poll still under way
                if local is not None:
                    local.clock.hold(None)  # after the cancel: the operation hands in no more
        metrics.continued = time.perf_counter()
        self._raise_lost(metrics, decision)
        outcome = Outcome(decision.winner, decision.result)
        return await continuation(outcome) if continuation else outcome

    async def _or_decision(
        self,
        metrics: StepMetrics,
        tasks: _StepTasks,
        op: asyncio.Task[Settled],
        local: _LocalOp | None,
    ) -> Decision:
        """Wait for the step's decision: claim it if ``op`` finishes first, else hear it.

        The designated member announces each decision once (one broadcast); a member that has
        not heard it within ``POLL_AFTER`` seconds (a long step, a subscription not yet known
        to the designated member, a lost link) asks for it, and so does every member after the
        designated member is lost.
        """
        heard = self.collectives.heard(self.run, metrics.step)
        designated = await self._designated()
        try:
            decision = await self._or_wait(metrics, tasks, op, heard, designated, local)
            if not heard.done():
                # Known here now (a claim's or a poll's answer), as if heard: should this
                # member become the designated one, it hands the decision on (see Collectives).
                heard.set_result(decision)
            return decision
        finally:
            # The designated member counts its announcement's deliveries (n-1, or none), and
            # in simulated time its questions.
            metrics.messages += self.collectives.sent(self.run, metrics.step)

    async def _or_wait(
        self,
        metrics: StepMetrics,
        tasks: _StepTasks,
        op: asyncio.Task[Settled],
        heard: asyncio.Future[Decision],
        designated: str,
        local: _LocalOp | None,
    ) -> Decision:
        poll: asyncio.Task[Settled] | None = None
        poll_at = time.monotonic() + POLL_AFTER
        while True:
            args = (self.run, metrics.step, self.me, self.members)
            try:
                if heard.done():
                    return heard.result()
                if poll is not None and poll.done():
                    return Decision.from_wire(poll.result().get())  # raises _Retry if failed
                ended = op.result() if op.done() else None
                if ended is not None and ended.error is None:
                    metrics.finished = metrics.finished or time.perf_counter()
                    when = () if local is None else (local.finished_at,)  # simulated time
                    answer = await self._ask(
                        metrics, designated, "mover.or_claim", *args, ended.value, *when
                    )
                    return Decision.from_wire(answer)
                waiting: set[asyncio.Future[Any]] = {heard}
                if not op.done():
                    waiting.add(op)
                if poll is not None:
                    waiting.add(poll)
                timeout = None if poll is not None else max(0.0, poll_at - time.monotonic())
                done, _ = await asyncio.wait(
                    waiting, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
                )
                if not done and poll is None:
                    poll = tasks.start(self._ask(metrics, designated, "mover.or_join", *args))
                elif op in done and op.result().error is not None:
                    log.warning(
                        "%s: the operation of step %d failed: %r",
                        self.me,
                        metrics.step,
                        op.result().error,
                    )
            except _Retry:
                await self._recover(designated)
                designated = await self._designated()
                if poll is not None:
                    poll.cancel()  # (if the retry came from a claim, a poll may be under way)
                poll, poll_at = None, time.monotonic()  # ask the (new) designated member now

    async def distributed_and(
        self,
        operation: Callable[[], Awaitable[Any]],
        continuation: Callable[[dict[str, Any]], Awaitable[Any]] | None = None,
        *,
        designated: bool = True,
    ) -> Any:
        """Run ``operation`` on every member; go on when all have finished, with all results.

        Returns ``{member: result}`` (an :class:`OperationFailed` for a member whose operation
        raised), or what ``continuation(results)`` returns. ``designated=False`` uses the
        all-to-all exchange (O(n^2) messages) instead of the designated member (O(n)).
        """
        metrics = self._begin("and" if designated else "and_all")
        error: BaseException | None = None
        try:
            result = await operation()
        except Exception as exc:
            error = exc
            result = OperationFailed(type(exc).__name__, str(exc))
        metrics.finished = time.perf_counter()
        wire = ["__failed__", result.type, result.message] if error else result
        timed = self.clock is not None and self.simulated
        # In simulated time a member that finished is idle while it waits, so that the world
        # neither waits for it nor moves on because of it: when the last one finishes, the
        # world holds still until all have been told.
        async with self.clock.waiting() if timed and self.clock else contextlib.nullcontext():
            if designated:
                decision = await self._and_designated(metrics, wire)
            else:
                decision = await self._and_all(metrics, wire)
        metrics.continued = time.perf_counter()
        self._raise_lost(metrics, decision)
        if timed:
            await self._rejoin()
        if error is not None:
            raise error
        results = {m: _unwire(r) for m, r in decision.results.items()}
        return await continuation(results) if continuation else results

    async def _and_designated(self, metrics: StepMetrics, result: Any) -> Decision:
        while True:
            designated = await self._designated()
            try:
                answer = await self._ask(
                    metrics,
                    designated,
                    "mover.and_done",
                    self.run,
                    metrics.step,
                    self.me,
                    self.members,
                    result,
                )
                return Decision.from_wire(answer)
            except _Retry:
                await self._recover(designated)

    async def _and_all(self, metrics: StepMetrics, result: Any) -> Decision:
        state = self.collectives.step(self.run, metrics.step, self.members)

        async def send(member: str) -> None:
            while member in self.node.team or not self.node.connected():
                try:
                    await self._ask(
                        metrics,
                        member,
                        "mover.and_put",
                        self.run,
                        metrics.step,
                        self.me,
                        self.members,
                        result,
                    )
                    return
                except _Retry:
                    await self._recover(member)

        self.collectives.and_put(self.run, metrics.step, self.me, self.members, result)
        # Leaving waits for every send (the others need this result, even once this member
        # has all of theirs); a send that fails for good fails the step, and cancels the rest.
        async with _StepTasks() as senders:
            for member in self.members:
                if member != self.me:
                    senders.spawn(send(member))
            return await asyncio.shield(state.decision)

    # -- helpers ------------------------------------------------------------------------------

    async def _rejoin(self) -> None:
        """After a ``distributed_and`` in simulated time: every member is engaged again before
        any goes on (step kind ``"rejoin"``), so that none misses a tick it would have acted
        in; nobody ticks meanwhile, so the world holds still. 2(n-1) messages."""
        metrics = self._begin("rejoin")
        decision = await self._and_designated(metrics, None)
        metrics.continued = time.perf_counter()
        self._raise_lost(metrics, decision)

    def _begin(self, kind: str) -> StepMetrics:
        self._step += 1
        metrics = StepMetrics(self._step, kind)
        self.metrics.append(metrics)
        return metrics

    async def _designated(self) -> str:
        if self.members == [self.me]:
            return self.me  # a team of one needs no links
        if not self.node.connected():  # never choose while cut off: every view is empty
            await self._recover(self.members)
        alive = [m for m in self.members if m == self.me or m in self.node.team]
        return alive[0]

    async def _ask(self, metrics: StepMetrics, member: str, procedure: str, *args: Any) -> Any:
        if member == self.me:  # the designated member is this one: no message
            handler = getattr(self.collectives, procedure.split(".")[1])
            result = handler(*args)
            return await result if asyncio.iscoroutine(result) else result
        metrics.requests += 1
        metrics.messages += 2
        try:
            # Bounded, and the member's liveliness ends it sooner: a poll that times out
            # is simply asked again (the designated member keeps the step).
            return await self.node.call(member, procedure, *args, timeout=CALL_TIMEOUT)
        except NotDelivered as exc:  # lost, unknown, timed out: find out why, then try again
            raise _Retry(str(exc)) from exc
        # An answered error (UnknownProcedure, BadArguments, Refused, RemoteError) propagates:
        # the member answers, and asking again would only get the same answer.

    async def _recover(self, member: str | Sequence[str]) -> None:
        reachable = await wait_reachable(self.node, member, self.stall_timeout)
        if not reachable and not self.node.connected():
            raise MemberLost(
                f"links lost for over {self.stall_timeout} s",
                members=frozenset(self.members) - {self.me},
            )
