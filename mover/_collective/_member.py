"""A member's side of the collective steps: :class:`TaskTeam`, the steps as a program calls them.

Every member runs the same steps in the same order; for each, it runs its operation (owned by
the step's :class:`~._group.StepTasks`), then claims, asks or waits for the decision that the
node's :class:`~._designated.Collectives` holds. What each step costs in messages, and why it
is safe: ``docs/collectives.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import logging
import random
import time
from collections.abc import Awaitable, Callable, Sequence
from typing import TYPE_CHECKING, Any

from .._exceptions import MemberLost, NotDelivered
from ._clock import RunClock, TimedOp, hold_here
from ._designated import Collectives
from ._designated_and import AND_DONE, AND_JOIN, AND_PUT
from ._designated_or import OR_CLAIM, OR_JOIN
from ._group import Settled, StepTasks
from ._reach import Retry, wait_lost, wait_reachable
from ._step import (
    CALL_TIMEOUT,
    POLL_AFTER,
    SEED_LIMIT,
    Decision,
    OperationFailed,
    Outcome,
    Policy,
    StepMetrics,
    seed_of,
    unwire,
)

if TYPE_CHECKING:
    from .._node import Node

log = logging.getLogger("mover.tasks")


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
        self._through(metrics, decision)
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

    def _through(self, metrics: StepMetrics, decision: Decision) -> None:
        """This member got through step ``metrics.step`` (its ``decision`` known here): raise
        MemberLost if the step lost a member."""
        self.collectives.got_through(self.run, metrics.step)
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
        clock = self.clock if self.simulated else None
        try:
            async with StepTasks() as tasks:  # leaving it awaits the losers' cleanup
                local = TimedOp(clock, operation, tasks.start) if clock is not None else None
                op = local.op if local is not None else tasks.start(operation())
                self.collectives.operations.reached(self.run, metrics.step, local)
                try:
                    decision = await self._or_decision(metrics, tasks, op, local)
                finally:
                    tasks.cancel()  # the losers' operations, a poll still under way
            # As the designated member, its questions of the step: ended (and awaited) too.
            await self.collectives.step_ended(self.run, metrics.step)
            metrics.continued = time.perf_counter()
            self._through(metrics, decision)
            if clock is not None:
                # Every member has stopped its operation before any goes on: a winner that
                # ticked at once could else let a loser's operation, not yet told, take one
                # more tick's readings (docs/reproducible-runs.md).
                await self._rejoin()
        finally:
            if clock is not None:
                clock.hold(None)  # held since its finish (the winner) or past it (a loser)
        outcome = Outcome(decision.winner, decision.result)
        return await continuation(outcome) if continuation else outcome

    async def _or_decision(
        self,
        metrics: StepMetrics,
        tasks: StepTasks,
        op: asyncio.Task[Settled],
        local: TimedOp | None,
    ) -> Decision:
        """Wait for the step's decision: claim it if ``op`` finishes first, else hear it.

        The designated member announces each decision once (one broadcast); a member that has
        not heard it within ``POLL_AFTER`` seconds (a long step, a subscription not yet known
        to the designated member, a lost link) asks for it, and so does every member after the
        designated member is lost.
        """
        heard = self.collectives.decision(self.run, metrics.step)
        designated = await self._designated()
        try:
            decision = await self._or_wait(metrics, tasks, op, heard, designated, local)
            # Known here now (perhaps from a claim's or a poll's answer): should this member
            # become the designated one, it hands the decision on.
            self.collectives.learned(self.run, metrics.step, decision)
            return decision
        finally:
            # The designated member counts its announcement's deliveries (n-1, or none), and
            # in simulated time its questions.
            metrics.messages += self.collectives.sent(self.run, metrics.step)

    async def _or_wait(
        self,
        metrics: StepMetrics,
        tasks: StepTasks,
        op: asyncio.Task[Settled],
        heard: asyncio.Future[Decision],
        designated: str,
        local: TimedOp | None,
    ) -> Decision:
        poll: asyncio.Task[Settled] | None = None
        poll_at = time.monotonic() + POLL_AFTER
        while True:
            args = (self.run, metrics.step, self.me, self.members)
            try:
                if heard.done():
                    return heard.result()
                if poll is not None and poll.done():
                    return Decision.from_wire(poll.result().get())  # raises Retry if failed
                ended = op.result() if op.done() else None
                if ended is not None and ended.error is None:
                    metrics.finished = metrics.finished or time.perf_counter()
                    when = () if local is None else (local.finished_at,)  # simulated time
                    answer = await self._ask(
                        metrics, designated, OR_CLAIM, *args, ended.value, *when
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
                    poll = tasks.start(self._ask(metrics, designated, OR_JOIN, *args))
                elif op in done and op.result().error is not None:
                    log.warning(
                        "%s: the operation of step %d failed: %r",
                        self.me,
                        metrics.step,
                        op.result().error,
                    )
            except Retry:
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
        timed = self.clock is not None and self.simulated
        if not designated:  # its record, served from the start: a loss is counted there
            self.collectives.serve(self.run, metrics.step, self.members, "and_all")
        told = self.collectives.decision(self.run, metrics.step)
        error: BaseException | None = None
        try:
            async with StepTasks() as tasks:
                op = tasks.start(self._held(operation) if timed else operation())
                if designated and self.collectives.policy_of(self.run) == "fail":
                    tasks.start(self._told_of_loss(metrics))  # sets ``told`` on a loss
                waiting: set[asyncio.Future[Any]] = {op, told}
                await asyncio.wait(waiting, return_when=asyncio.FIRST_COMPLETED)
                tasks.cancel()  # the operation, if the step was decided meanwhile (a loss)
            if told.done():  # decided while this member was in its operation: it was lost
                metrics.finished = time.perf_counter()
                decision = told.result()
            else:
                ended = op.result()
                metrics.finished = time.perf_counter()
                error = ended.error
                if error is None:
                    wire = ended.value
                else:
                    wire = OperationFailed(type(error).__name__, str(error)).to_wire()
                # In simulated time a member that finished is idle while it waits, so that
                # the world neither waits for it nor moves on because of it: when the last
                # one finishes, the world holds still until all have been told.
                idle = self.clock.idling() if timed and self.clock else contextlib.nullcontext()
                async with idle:
                    if designated:
                        decision = await self._and_designated(metrics, wire)
                    else:
                        decision = await self._and_all(metrics, wire)
            metrics.continued = time.perf_counter()
            self._through(metrics, decision)
            if timed:
                await self._rejoin()
        finally:
            if timed and self.clock is not None:
                self.clock.hold(None)  # held since its operation ended (see _held)
        if error is not None:
            raise error
        results = {m: unwire(r) for m, r in decision.results.items()}
        return await continuation(results) if continuation else results

    async def _held(self, operation: Callable[[], Awaitable[Any]]) -> Any:
        """``operation``, then this member's clock held where it ended, with no loop turn in
        between (:func:`hold_here`)."""
        try:
            return await operation()
        finally:
            assert self.clock is not None
            hold_here(self.clock)

    async def _told_of_loss(self, metrics: StepMetrics) -> None:
        """While this member is in its operation of AND step ``metrics.step``: once a member
        of the team is lost, ask the designated member for the decision (which the loss fails),
        and make it known here (2 messages, only after a loss)."""
        await wait_lost(self.node, self.members)
        while True:
            designated = await self._designated()
            args = (self.run, metrics.step, self.me, self.members)
            try:
                answer = await self._ask(metrics, designated, AND_JOIN, *args)
                break
            except Retry:
                await self._recover(designated)
        self.collectives.learned(self.run, metrics.step, Decision.from_wire(answer))

    async def _and_designated(self, metrics: StepMetrics, result: Any) -> Decision:
        while True:
            designated = await self._designated()
            try:
                answer = await self._ask(
                    metrics,
                    designated,
                    AND_DONE,
                    self.run,
                    metrics.step,
                    self.me,
                    self.members,
                    result,
                )
                decision = Decision.from_wire(answer)
                # Known here now: a member back from a stall may ask (Collectives.run_lost).
                self.collectives.learned(self.run, metrics.step, decision)
                return decision
            except Retry:
                await self._recover(designated)

    async def _and_all(self, metrics: StepMetrics, result: Any) -> Decision:
        state = self.collectives.serve(self.run, metrics.step, self.members, "and_all")

        async def send(member: str) -> None:
            while member in self.node.membership or not self.node.connected():
                try:
                    await self._ask(
                        metrics,
                        member,
                        AND_PUT,
                        self.run,
                        metrics.step,
                        self.me,
                        self.members,
                        result,
                    )
                    return
                except Retry:
                    await self._recover(member)

        self.collectives.ands.put(self.run, metrics.step, self.me, self.members, result)
        # Leaving waits for every send (the others need this result, even once this member
        # has all of theirs); a send that fails for good fails the step, and cancels the rest.
        async with StepTasks() as senders:
            for member in self.members:
                if member != self.me:
                    senders.spawn(send(member))
            return await asyncio.shield(state.decision)

    # -- helpers ------------------------------------------------------------------------------

    async def _rejoin(self) -> None:
        """After a ``distributed_and`` in simulated time: every member is engaged again before
        any goes on (step kind ``"rejoin"``), so that none misses a tick it would have acted
        in; after a ``distributed_or`` in simulated time: every member has stopped its
        operation before any goes on. Nobody ticks meanwhile, so the world holds still.
        2(n-1) messages."""
        metrics = self._begin("rejoin")
        decision = await self._and_designated(metrics, None)
        metrics.continued = time.perf_counter()
        self._through(metrics, decision)

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
        alive = [m for m in self.members if m == self.me or m in self.node.membership]
        return alive[0]

    async def _ask(self, metrics: StepMetrics, member: str, procedure: str, *args: Any) -> Any:
        if member == self.me:  # the designated member is this one: no message
            result = self.collectives.procedures[procedure](*args)
            return await result if inspect.isawaitable(result) else result
        metrics.requests += 1
        metrics.messages += 2
        try:
            # Bounded, and the member's liveliness ends it sooner: a poll that times out
            # is simply asked again (the designated member keeps the step).
            return await self.node.call(member, procedure, *args, timeout=CALL_TIMEOUT)
        except NotDelivered as exc:  # lost, unknown, timed out: find out why, then try again
            raise Retry(str(exc)) from exc
        # An answered error (UnknownProcedure, BadArguments, Refused, RemoteError) propagates:
        # the member answers, and asking again would only get the same answer.

    async def _recover(self, member: str | Sequence[str]) -> None:
        reachable = await wait_reachable(self.node, member, self.stall_timeout)
        if not reachable and not self.node.connected():
            raise MemberLost(
                f"links lost for over {self.stall_timeout} s",
                members=frozenset(self.members) - {self.me},
            )
