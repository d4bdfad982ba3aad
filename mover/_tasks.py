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
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

from ._exceptions import MemberLost, NotDelivered, WireError

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.tasks")

Policy = Literal["fail", "survivors"]
_STEP_MEMORY = 512  # finished steps a designated member remembers (for late re-sends)
DECIDED_TOPIC = "mover/decided"
LOST_GRACE = 0.5  # seconds a member must stay gone (while this node is linked) to be lost
CALL_TIMEOUT = 30.0  # seconds a collective's call waits before it is asked again
POLL_AFTER = 0.2  # seconds an OR member waits for the announced decision before polling


@dataclass(frozen=True)
class Outcome:
    """The result of a ``distributed_or`` step: who won and what its operation returned."""

    winner: str
    result: Any


@dataclass(frozen=True)
class OperationFailed:
    """Stands in a ``distributed_and`` result for a member whose operation raised."""

    type: str
    message: str


@dataclass
class StepMetrics:
    """What one member sent for one step (sum over members for the step's total)."""

    step: int
    kind: str
    requests: int = 0  # envelopes this member sent as requests
    messages: int = 0  # requests and the replies they got
    started: float = field(default_factory=time.perf_counter)
    finished: float = 0.0  # local operation finished (perf_counter)
    continued: float = 0.0  # the step's outcome known here (perf_counter)


# -- the designated member's side -----------------------------------------------------------------


@dataclass(frozen=True)
class Decision:
    """A step's decision: who won an OR (``won``), every result of an AND (``all``), or who
    was lost (``lost``). One type from the designated member to every member; on the wire a
    map (:meth:`to_wire`), read back by :meth:`from_wire`, which refuses anything else."""

    kind: Literal["won", "all", "lost"]
    winner: str = ""
    result: Any = None
    results: dict[str, Any] = field(default_factory=dict)
    lost: tuple[str, ...] = ()

    def to_wire(self) -> dict[str, Any]:
        """The decision as a msgpack-able map."""
        if self.kind == "won":
            return {"kind": "won", "winner": self.winner, "result": self.result}
        if self.kind == "all":
            return {"kind": "all", "results": self.results}
        return {"kind": "lost", "lost": list(self.lost)}

    @classmethod
    def from_wire(cls, value: Any) -> Decision:
        """The decision in ``value``; raise WireError if it is not one."""
        kind = value.get("kind") if isinstance(value, dict) else None
        if kind == "won" and isinstance(value.get("winner"), str):
            return cls("won", winner=value["winner"], result=value.get("result"))
        if kind == "all" and isinstance(value.get("results"), dict):
            results = value["results"]
            if all(isinstance(m, str) for m in results):
                return cls("all", results=results)
        if kind == "lost" and isinstance(value.get("lost"), list):
            lost = value["lost"]
            if all(isinstance(m, str) for m in lost):
                return cls("lost", lost=tuple(lost))
        raise WireError(f"not a decision: {value!r:.80}")


@dataclass
class _Step:
    members: frozenset[str]
    joined: set[str] = field(default_factory=set)
    claims: list[tuple[str, Any]] = field(default_factory=list)
    results: dict[str, Any] = field(default_factory=dict)
    decision: asyncio.Future[Decision] = field(
        default_factory=lambda: asyncio.get_running_loop().create_future()
    )
    takeover: bool = False  # this member took over from a designated member that is gone
    lost: list[str] = field(default_factory=list)  # members already gone when it took over
    announced: int = 0  # deliveries of the OR decision's broadcast (n-1, or 0 if none was sent)
    told: bool = False  # the OR decision was announced (or needed no announcement)


class Collectives:
    """One per node: serves the steps this node is designated for (or receives, all-to-all)."""

    def __init__(self, node: Node, policy: Policy = "fail") -> None:
        self.node = node
        self.policy = policy
        self._steps: dict[tuple[str, int], _Step] = {}
        # OR decisions as announced by designated members (one broadcast per step)
        self._heard: dict[tuple[str, int], asyncio.Future[Decision]] = {}
        self._announcements = node.subscribe(DECIDED_TOPIC)
        self._listener = asyncio.get_running_loop().create_task(self._listen())
        node.export(self.or_join, "mover.or_join")
        node.export(self.or_claim, "mover.or_claim")
        node.export(self.and_done, "mover.and_done")
        node.export(self.and_put, "mover.and_put")
        # Only a member gone for LOST_GRACE counts as lost: when a router restarts, every
        # member sees the others leave a moment before it sees its own link go.
        node.team.on_gone(self._member_left, grace=LOST_GRACE)

    def step(self, run: str, step: int, members: Sequence[str], kind: str = "and") -> _Step:
        key = (run, step)
        state = self._steps.get(key)
        if state is None:
            state = self._steps[key] = _Step(frozenset(members))
            if kind == "or":
                state.decision.add_done_callback(lambda _: self._announce(run, step, state))
            state.lost = [m for m in members if m < self.node.name and m not in self.node.team]
            state.takeover = bool(state.lost)
            heard = self._heard.get(key)
            if state.takeover and heard is not None and heard.done():
                # A successor that heard the lost member's announcement decides the same at
                # once: the members that moved on with it will never ask.
                state.decision.set_result(heard.result())
            while len(self._steps) > _STEP_MEMORY:
                # The oldest goes, decided or not: a member that opens steps that are never
                # decided (a bug, or a member gone rogue) cannot make this one hold them all.
                old_key, old = next(iter(self._steps.items()))
                del self._steps[old_key]
                if not old.decision.done():
                    log.warning(
                        "%s: step %s of run %r never decided: dropped",
                        self.node.name,
                        old_key[1],
                        old_key[0],
                    )
                    old.decision.set_exception(
                        MemberLost(f"step {old_key[1]} of run {old_key[0]!r} was never decided")
                    )
                    old.decision.exception()  # retrieved: it may have no waiter left
        return state

    def heard(self, run: str, step: int) -> asyncio.Future[Decision]:
        """The decision of OR step ``(run, step)`` once announced (a future)."""
        future = self._heard.get((run, step))
        if future is None:
            future = self._heard[(run, step)] = asyncio.get_running_loop().create_future()
            while len(self._heard) > _STEP_MEMORY:
                del self._heard[next(iter(self._heard))]
        return future

    async def _listen(self) -> None:
        async for message in self._announcements:
            data = message.data
            try:  # any decodable frame may come: only a well-formed decision counts
                if not (
                    isinstance(data, list)
                    and len(data) == 3
                    and isinstance(data[0], str)
                    and type(data[1]) is int
                ):
                    raise WireError("not [run, step, decision]")
                decision = Decision.from_wire(data[2])
            except WireError as exc:
                self.node._refusal_log.warn(message.sender, f"dropped a decision: {exc}")
                continue
            future = self.heard(data[0], data[1])
            if not future.done():
                future.set_result(decision)

    def _announce(self, run: str, step: int, state: _Step) -> None:
        """Tell the members the decision: one broadcast, unless every one of them has asked."""
        if state.told:
            return
        state.told = True
        if state.decision.exception() is not None:
            return  # dropped undecided (see step): its waiters were told
        decision = state.decision.result()
        local = self.heard(run, step)
        if not local.done():
            local.set_result(decision)
        others = state.members - {self.node.name}
        if not others <= state.joined:  # those who asked (or claimed) get it in their answer
            wire = [run, step, decision.to_wire()]
            self.node.broadcast_nowait(DECIDED_TOPIC, wire, reliable=True)
            state.announced = len(others)

    def announced(self, run: str, step: int) -> int:
        """How many deliveries the announcement of OR step ``(run, step)`` made from here."""
        state = self._steps.get((run, step))
        if state is None:
            return 0
        if state.decision.done():
            self._announce(run, step, state)  # now, if its callback has not run yet
        return state.announced

    def _expected(self, state: _Step) -> set[str]:
        return {m for m in state.members if m in self.node.team}

    async def or_join(self, run: str, step: int, member: str, members: list[str]) -> Any:
        """A member waits for the decision."""
        state = self.step(run, step, members, "or")
        state.joined.add(member)
        self._maybe_decide(state)
        return (await asyncio.shield(state.decision)).to_wire()

    async def or_claim(
        self, run: str, step: int, member: str, members: list[str], result: Any
    ) -> Any:
        """A member finished its operation: it wins unless someone claimed first."""
        state = self.step(run, step, members, "or")
        state.joined.add(member)
        if all(m != member for m, _ in state.claims):
            state.claims.append((member, result))
        self._maybe_decide(state)
        return (await asyncio.shield(state.decision)).to_wire()

    def _maybe_decide(self, state: _Step) -> None:
        if state.decision.done():
            return
        if state.takeover:
            if not self._expected(state) <= state.joined:
                return  # a successor decides only once every live member has said what it knows
            if state.lost and self.policy == "fail":
                state.decision.set_result(Decision("lost", lost=tuple(state.lost)))
                return
        if state.claims:
            winner, result = state.claims[0]
            state.decision.set_result(Decision("won", winner=winner, result=result))

    async def and_done(
        self, run: str, step: int, member: str, members: list[str], result: Any
    ) -> Any:
        """A member finished: record its result; answer when every live member has."""
        state = self.step(run, step, members)
        state.results[member] = result
        self._maybe_complete(state)
        return (await asyncio.shield(state.decision)).to_wire()

    def and_put(self, run: str, step: int, member: str, members: list[str], result: Any) -> None:
        """All-to-all: a member's result, sent to every other member."""
        state = self.step(run, step, members)
        state.results[member] = result
        self._maybe_complete(state)

    def _maybe_complete(self, state: _Step) -> None:
        if state.decision.done():
            return
        if state.lost and self.policy == "fail":
            state.decision.set_result(Decision("lost", lost=tuple(state.lost)))
            return
        expected = self._expected(state) | state.results.keys() & state.members
        if self.policy == "fail" and not state.members <= expected:
            return  # _member_left decides the failure
        if expected and expected <= state.results.keys():
            results = {m: state.results[m] for m in sorted(expected)}
            state.decision.set_result(Decision("all", results=results))

    def _member_left(self, name: str) -> None:
        if not self.node.connected():
            return  # we are cut off, not they: stall (see the module docstring)
        for state in list(self._steps.values()):
            if state.decision.done() or name not in state.members:
                continue
            alive = self._expected(state)
            if not alive:
                state.decision.set_result(Decision("lost", lost=tuple(sorted(state.members))))
            elif self.policy == "fail" and name not in state.results:
                state.decision.set_result(Decision("lost", lost=(name,)))
            else:
                self._maybe_decide(state)
                self._maybe_complete(state)


# -- a member's side ------------------------------------------------------------------------------


class TaskTeam:
    """The members of one program run, and the collective steps among them.

    ``members`` must be the same list on every member; ``run`` names the run (the same on every
    member). ``stall_timeout`` bounds how long a step waits for lost links to come back.
    A node serves collectives through one :class:`Collectives` (it exports fixed procedure
    names): when a node takes part in several runs, pass the same ``collectives`` to each
    (``ProgramHost`` does); without it, a new one is made and replaces the previous one.
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
    ) -> None:
        if node.name not in members:
            raise ValueError(f"{node.name!r} is not one of the members {list(members)!r}")
        self.node = node
        self.run = run
        self.members = sorted(set(members))
        self.collectives = collectives or Collectives(node, policy)
        self.stall_timeout = stall_timeout
        self.metrics: list[StepMetrics] = []
        self._step = 0

    @property
    def me(self) -> str:
        """This member's name."""
        return self.node.name

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
        op = asyncio.ensure_future(operation())
        try:
            decision = await self._or_decision(metrics, op)
        finally:
            if not op.done():
                op.cancel()
            await asyncio.gather(op, return_exceptions=True)  # the losers' cleanup runs here
        metrics.continued = time.perf_counter()
        if decision.kind == "lost":
            raise MemberLost(
                f"step {metrics.step} of run {self.run!r} lost {list(decision.lost)}",
                members=frozenset(decision.lost),
            )
        outcome = Outcome(decision.winner, decision.result)
        return await continuation(outcome) if continuation else outcome

    async def _or_decision(self, metrics: StepMetrics, op: asyncio.Future[Any]) -> Decision:
        """Wait for the step's decision: claim it if ``op`` finishes first, else hear it.

        The designated member announces each decision once (one broadcast); a member that has
        not heard it within ``POLL_AFTER`` seconds (a long step, a subscription not yet known
        to the designated member, a lost link) asks for it, and so does every member after the
        designated member is lost.
        """
        heard = self.collectives.heard(self.run, metrics.step)
        designated = await self._designated()
        try:
            return await self._or_wait(metrics, op, heard, designated)
        finally:
            # The designated member counts its announcement's deliveries (n-1, or none).
            metrics.messages += self.collectives.announced(self.run, metrics.step)

    async def _or_wait(
        self,
        metrics: StepMetrics,
        op: asyncio.Future[Any],
        heard: asyncio.Future[Decision],
        designated: str,
    ) -> Decision:
        poll: asyncio.Future[Any] | None = None
        poll_at = time.monotonic() + POLL_AFTER
        while True:
            args = (self.run, metrics.step, self.me, self.members)
            try:
                if heard.done():
                    return heard.result()
                if poll is not None and poll.done():
                    return Decision.from_wire(poll.result())  # raises _Retry if it failed
                if op.done() and not op.cancelled() and op.exception() is None:
                    metrics.finished = metrics.finished or time.perf_counter()
                    answer = await self._ask(
                        metrics, designated, "mover.or_claim", *args, op.result()
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
                    poll = asyncio.ensure_future(
                        self._ask(metrics, designated, "mover.or_join", *args)
                    )
                    poll.add_done_callback(_quiet)
                elif op in done and op.exception() is not None:
                    log.warning(
                        "%s: the operation of step %d failed: %r",
                        self.me,
                        metrics.step,
                        op.exception(),
                    )
            except _Retry:
                await self._recover(designated)
                designated = await self._designated()
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
        if designated:
            decision = await self._and_designated(metrics, wire)
        else:
            decision = await self._and_all(metrics, wire)
        metrics.continued = time.perf_counter()
        if decision.kind == "lost":
            raise MemberLost(
                f"step {metrics.step} of run {self.run!r} lost {list(decision.lost)}",
                members=frozenset(decision.lost),
            )
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
        senders = [asyncio.ensure_future(send(m)) for m in self.members if m != self.me]
        try:
            return await asyncio.shield(state.decision)
        finally:
            await asyncio.gather(*senders, return_exceptions=True)

    # -- helpers ------------------------------------------------------------------------------

    def _begin(self, kind: str) -> StepMetrics:
        self._step += 1
        metrics = StepMetrics(self._step, kind)
        self.metrics.append(metrics)
        return metrics

    async def _designated(self) -> str:
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


async def wait_reachable(
    node: Node, member: str | Sequence[str], stall_timeout: float = 60.0
) -> bool:
    """After a failed call to ``member``: wait out an outage; True if it is a member again.

    A member gone while this node is linked to others is gone (False at once). If this node
    has lost every link, wait up to ``stall_timeout`` for the links, then a moment for
    ``member`` (or every one of several) to be seen again.
    """
    wanted = {member} if isinstance(member, str) else set(member)
    grace = time.monotonic() + 0.5
    while node.connected():
        # A failed call and a lost link can be seen in either order: wait a moment to tell a
        # member that is gone (we stay linked) from an outage (our links go too).
        if wanted <= node.team.members():
            return True
        if time.monotonic() > grace:
            return False
        await asyncio.sleep(0.02)
    log.warning("%s: links lost: stalling", node.name)
    deadline = time.monotonic() + stall_timeout
    while not node.connected():  # zenoh offers no event for this: poll
        if time.monotonic() > deadline:
            return False
        await asyncio.sleep(0.05)
    settle = time.monotonic() + 2.0
    while not wanted <= node.team.members() and time.monotonic() < settle:  # noqa: ASYNC110
        await asyncio.sleep(0.05)
    back = wanted <= node.team.members()
    log.info("%s: links back; %s %s", node.name, sorted(wanted), "back" if back else "gone")
    return back


def _quiet(task: asyncio.Future[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieved: a poll nobody waits for any more may fail quietly


class _Retry(Exception):
    """A collective's call was not delivered: recover, then ask (the new designated) again."""


def _unwire(value: Any) -> Any:
    if isinstance(value, list) and len(value) == 3 and value[0] == "__failed__":
        return OperationFailed(str(value[1]), str(value[2]))
    return value
