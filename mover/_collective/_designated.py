"""The node's side of the collective steps: one :class:`Collectives` per node.

It owns every step's record on this node (:class:`~._step.Step`) and is the only writer of
its decision, whichever way the decision becomes known here: decided as the step's designated
member (from the claims, polls and results of the others; announced at once, in one broadcast),
heard in another's announcement, or told to this node's own member in an answer. It asks the
others ``or_passed``, in one TaskGroup (:class:`~._operations.Operations` answers it). Protocol
and costs: ``docs/collectives.md``. Memory: the last ``STEP_MEMORY`` steps.
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from .._exceptions import (
    Answered,
    CallTimeout,
    MemberLost,
    NotDelivered,
    RemoteError,
    WireError,
)
from .._futures import failure
from .._session import FaultLog
from ._operations import Operations
from ._reach import wait_reachable
from ._step import (
    CALL_TIMEOUT,
    DECIDED_TOPIC,
    LOST_GRACE,
    STEP_MEMORY,
    Decision,
    Policy,
    Step,
)

if TYPE_CHECKING:
    from .._node import Node

log = logging.getLogger("mover.tasks")

OR_JOIN = "mover.or_join"
OR_CLAIM = "mover.or_claim"
OR_PASSED = "mover.or_passed"
AND_DONE = "mover.and_done"
AND_PUT = "mover.and_put"


class Collectives:
    """One per node: serves the steps this node is designated for (or receives, all-to-all),
    and holds each step's decision as known here."""

    def __init__(self, node: Node, policy: Policy = "fail") -> None:
        self.node = node
        self.policy = policy  # for runs not given their own (:meth:`set_policy`)
        self._policies: dict[str, Policy] = {}  # run -> its policy, the latest STEP_MEMORY runs
        self._steps: dict[tuple[str, int], Step] = {}
        self.operations = Operations()  # this member's, for the designated one's or_passed
        self._faults = FaultLog(node.name)
        self._questions: asyncio.TaskGroup | None = None  # owns the or_passed questions
        self._closed = False
        self._announcements = node.subscribe(DECIDED_TOPIC)
        self._listener = asyncio.get_running_loop().create_task(self._serve())
        #: The procedures, by their wire name: exported, and called directly by this node's
        #: own member when it is the designated one (no message).
        self.procedures: dict[str, Callable[..., Any]] = {
            OR_JOIN: self.or_join,
            OR_CLAIM: self.or_claim,
            OR_PASSED: self.operations.or_passed,
            AND_DONE: self.and_done,
            AND_PUT: self.and_put,
        }
        for name, procedure in self.procedures.items():
            node.export(procedure, name)
        # Only a member gone for LOST_GRACE counts as lost: when a router restarts, every
        # member sees the others leave a moment before it sees its own link go.
        node.membership.on_gone(self._member_left, grace=LOST_GRACE)

    # -- each step's record, and its decision ------------------------------------------------

    def _record(self, run: str, step: int) -> Step:
        key = (run, step)
        state = self._steps.get(key)
        if state is None:
            state = self._steps[key] = Step(run, step)
            if len(self._steps) > STEP_MEMORY:
                self._forget_one()
        return state

    def _forget_one(self) -> None:
        """Drop the oldest record but the newest that is decided or not served here (heard
        decisions of others' runs must not push out a long step served here), else the oldest
        served one, decided or not: a member that opens steps that are never decided (a bug,
        or a member gone rogue) cannot make this one hold them all."""
        older = list(self._steps.items())[:-1]
        key = next((k for k, st in older if st.decision.done() or not st.served), older[0][0])
        old = self._steps.pop(key)
        if old.served and not old.decision.done():
            run, step = key
            log.warning("%s: step %s of run %r never decided: dropped", self.node.name, step, run)
            old.decision.set_exception(MemberLost(f"step {step} of run {run!r} was never decided"))
            failure(old.decision)  # retrieved: it may have no waiter left
            old.told = True  # its waiters were told, and there is nothing to announce
            _cancel_all(old.asking)

    def decision(self, run: str, step: int) -> asyncio.Future[Decision]:
        """The decision of step ``(run, step)`` once known here (a future; read only)."""
        return self._record(run, step).decision

    def learned(self, run: str, step: int, decision: Decision) -> None:
        """This node's member learned the decision of OR step ``(run, step)`` in an answer: it
        is known here now, as if heard (should this node become the designated member, it
        hands the decision on)."""
        state = self._record(run, step)
        if not state.decision.done():
            self._decide(state, decision)

    def _decide(self, state: Step, decision: Decision) -> None:
        """The one writer of a step's decision (decided here, heard, or learned)."""
        state.decision.set_result(decision)
        if state.served:
            self._tell(state)

    def _tell(self, state: Step) -> None:
        """A served OR step is decided: stop asking, and tell the members the decision, in one
        broadcast unless every one of them asked (they get it in their answer). Once."""
        if state.kind != "or" or state.told:
            return
        state.told = True
        _cancel_all(state.asking)
        others = state.members - {self.node.name}
        if not others <= state.joined:
            wire = [state.run, state.step, state.decision.result().to_wire()]
            self.node.broadcast_nowait(DECIDED_TOPIC, wire, reliable=True)
            state.announced = len(others)

    def serve(self, run: str, step: int, members: Sequence[str], kind: str = "and") -> Step:
        """The record of step ``(run, step)``, served here as its designated member (or, for an
        all-to-all AND, as one of its receivers)."""
        state = self._record(run, step)
        if not state.served:
            state.served, state.kind, state.members = True, kind, frozenset(members)
            name = self.node.name
            state.lost = [m for m in members if m < name and m not in self.node.membership]
            state.takeover = bool(state.lost)
        return state

    def sent(self, run: str, step: int) -> int:
        """Messages OR step ``(run, step)`` cost from here as its designated member: the
        announcement's deliveries and the ``or_passed`` questions with their answers."""
        state = self._steps.get((run, step))
        return 0 if state is None else state.announced + 2 * state.questions

    async def _serve(self) -> None:
        """Hear the announcements, and own the questions (until the node closes)."""
        async with asyncio.TaskGroup() as questions:
            self._questions = questions
            try:
                await self._listen()
            finally:
                self._closed, self._questions = True, None
                for state in self._steps.values():
                    _cancel_all(state.asking)  # nobody is left to tell their answers to

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
                self._faults.warn(message.sender, f"dropped a decision: {exc}")
                continue
            state = self._record(data[0], data[1])
            if not state.decision.done():
                self._decide(state, decision)  # heard: another member decided it

    def start_run(self, run: str) -> None:
        """A run named ``run`` starts here: forget what an earlier run of that name left (its
        decided steps, heard decisions, operations; that it ended). What other members already
        sent for the new run stays: it cannot be decided before this member began."""
        self.operations.start_run(run)
        for key in [k for k, st in self._steps.items() if k[0] == run and st.decision.done()]:
            del self._steps[key]

    def set_policy(self, run: str, policy: Policy) -> None:
        """Run ``run``'s steps follow ``policy`` (every member of it is started with the same)."""
        self._policies[run] = policy
        while len(self._policies) > STEP_MEMORY:
            del self._policies[next(iter(self._policies))]

    def _fails(self, state: Step) -> bool:
        """Whether a lost member fails ``state``'s step (policy ``fail``)."""
        return self._policies.get(state.run, self.policy) == "fail"

    def end_run(self, run: str) -> None:
        """Run ``run`` ended here: questions about its steps are answered "out" from now on."""
        self.operations.end_run(run)

    # -- the designated member: OR -----------------------------------------------------------

    def _ask_passed(self, state: Step, member: str, t: float) -> None:
        task = state.asking.get(member)
        if task is not None and not task.done():
            return  # one question at a time: a later answer covers an earlier time
        if self._questions is None:
            if not self._closed:  # the owner of the questions starts with the next loop turn
                asyncio.get_running_loop().call_soon(self._ask_passed, state, member, t)
            return
        state.asking[member] = self._questions.create_task(self._question(state, member, t))

    async def _question(self, state: Step, member: str, t: float) -> None:
        try:
            await self._passed_from(state, member, t)
        except Exception as exc:  # a question that fails is not the other questions' concern
            log.debug("%s: or_passed to %s failed: %r", self.node.name, member, exc)

    async def _passed_from(self, state: Step, member: str, t: float) -> None:
        while not state.decision.done():
            try:
                if member == self.node.name:
                    answer = await self.operations.or_passed(state.run, state.step, t)
                else:
                    state.questions += 1
                    answer = await self.node.call(
                        member, OR_PASSED, state.run, state.step, t, timeout=CALL_TIMEOUT
                    )
            except CallTimeout:
                continue  # it is alive (liveness ends the call sooner): ask again
            except (NotDelivered, RemoteError) as exc:
                if isinstance(exc, RemoteError) and exc.remote_type != "Cancelled":
                    # it answers, but cannot say its time (no clock, a bug): it never claims
                    log.warning("%s: %s cannot say its time: %s", self.node.name, member, exc)
                    answer = {"out": True}
                elif await wait_reachable(self.node, member):
                    continue  # lost for a moment, or its call was cancelled as it closed
                else:
                    return  # gone: _member_left decides, as for any step
            except Answered as exc:
                log.warning("%s: %s cannot say its time: %s", self.node.name, member, exc)
                answer = {"out": True}
            if not isinstance(answer, dict):
                answer = {"out": True}
            finished = answer.get("finished")
            if isinstance(finished, (int, float)):
                state.finished[member] = float(finished)
            elif "passed" in answer:
                state.beyond[member] = max(t, state.beyond.get(member, -math.inf))
            else:
                state.beyond[member] = math.inf
            self._maybe_decide(state)
            return

    def _expected(self, state: Step) -> set[str]:
        return {m for m in state.members if m in self.node.membership}

    async def or_join(self, run: str, step: int, member: str, members: list[str]) -> Any:
        """A member waits for the decision."""
        state = self.serve(run, step, members, "or")
        state.joined.add(member)
        self._maybe_decide(state)
        return (await asyncio.shield(state.decision)).to_wire()

    async def or_claim(
        self,
        run: str,
        step: int,
        member: str,
        members: list[str],
        result: Any,
        finished_at: float | None = None,
    ) -> Any:
        """A member finished its operation: it wins unless someone claimed first (or, with a
        ``finished_at``, finished earlier in simulated time: see docs/collectives.md)."""
        state = self.serve(run, step, members, "or")
        state.joined.add(member)
        if finished_at is not None:
            state.timed = True
        if all(m != member for m, _, _ in state.claims):
            state.claims.append((member, result, finished_at))
        self._maybe_decide(state)
        return (await asyncio.shield(state.decision)).to_wire()

    def _maybe_decide(self, state: Step) -> None:
        if state.decision.done():
            # Known before this node served the step (heard, or told as a member): a
            # successor hands that decision on, since the members that moved on with it
            # will never ask.
            self._tell(state)
            return
        if state.takeover:
            if not self._expected(state) <= state.joined:
                return  # a successor decides only once every live member has said what it knows
            if state.lost and self._fails(state):
                self._decide(state, Decision("lost", lost=tuple(state.lost)))
                return
        if not state.claims:
            return
        if state.timed:
            self._maybe_decide_timed(state)
            return
        winner, result, _ = state.claims[0]
        self._decide(state, Decision("won", winner=winner, result=result))

    def _maybe_decide_timed(self, state: Step) -> None:
        """Decide once every live member claimed or went past the earliest claimed time."""

        def key(claim: tuple[str, Any, float | None]) -> tuple[float, str]:
            return (math.inf if claim[2] is None else claim[2], claim[0])

        winner, result, t = min(state.claims, key=key)
        at = math.inf if t is None else t
        # A member that is gone but not yet lost (on_gone's grace) may have finished first:
        # it is waited for, and its loss then decides as in any step.
        out = {m for m, _, _ in state.claims} | state.gone | set(state.lost)
        pending = [
            m
            for m in sorted(state.members - out)
            if state.beyond.get(m, -math.inf) < at and state.finished.get(m, -math.inf) <= at
        ]
        if not pending:
            self._decide(state, Decision("won", winner=winner, result=result))
            return
        for member in pending:
            # a member that finished in time: its claim is coming; one that is gone cannot say
            if member not in state.finished and member in self.node.membership:
                self._ask_passed(state, member, at)

    # -- the designated member: AND ----------------------------------------------------------

    async def and_done(
        self, run: str, step: int, member: str, members: list[str], result: Any
    ) -> Any:
        """A member finished: record its result; answer when every live member has."""
        state = self.serve(run, step, members)
        state.results[member] = result
        self._maybe_complete(state)
        return (await asyncio.shield(state.decision)).to_wire()

    def and_put(self, run: str, step: int, member: str, members: list[str], result: Any) -> None:
        """All-to-all: a member's result, sent to every other member."""
        state = self.serve(run, step, members)
        state.results[member] = result
        self._maybe_complete(state)

    def _maybe_complete(self, state: Step) -> None:
        if state.decision.done():
            return
        if state.lost and self._fails(state):
            self._decide(state, Decision("lost", lost=tuple(state.lost)))
            return
        expected = self._expected(state) | state.results.keys() & state.members
        if self._fails(state) and not state.members <= expected:
            return  # _member_left decides the failure
        if expected and expected <= state.results.keys():
            results = {m: state.results[m] for m in sorted(expected)}
            self._decide(state, Decision("all", results=results))

    def _member_left(self, name: str) -> None:
        if not self.node.connected():
            return  # we are cut off, not they: stall (see docs/collectives.md, Failures)
        for state in list(self._steps.values()):
            if not state.served or state.decision.done() or name not in state.members:
                continue
            state.gone.add(name)
            alive = self._expected(state)
            if not alive:
                self._decide(state, Decision("lost", lost=tuple(sorted(state.members))))
            elif self._fails(state) and name not in state.results:
                self._decide(state, Decision("lost", lost=(name,)))
            else:
                self._maybe_decide(state)
                self._maybe_complete(state)


def _cancel_all(tasks: dict[str, asyncio.Task[None]]) -> None:
    for task in tasks.values():
        task.cancel()
