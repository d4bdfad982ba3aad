"""The node's side of the collective steps: one :class:`Collectives` per node.

It owns every step's record on this node (:class:`~._step.Step`) and is the only writer of
its decision, whichever way the decision becomes known here: decided as the step's designated
member (from the claims, polls and results of the others; announced at once, in one broadcast),
heard in another's announcement, or told to this node's own member in an answer. Its parts
decide: :class:`~._designated_or.OrSteps` the OR steps served here,
:class:`~._designated_and.AndSteps` the AND steps, and :class:`~._questions.Questions` asks the
members what the step waits for (``or_passed``; ``step_known``, taking a step over from a
designated member that is gone). A served step's questions run in a TaskGroup of the step's own,
which ends, awaited, when the step is decided; the steps' groups belong to one TaskGroup of the
node's. A member lost at any moment fails (policy ``fail``) every undecided step it is a member
of, served here already or later (it is remembered, while it stays gone). Protocol and costs:
``docs/collectives.md``. Memory: the last ``STEP_MEMORY`` steps and runs.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from .._exceptions import MemberLost, MoverError, WireError
from .._futures import failure
from .._ratelog import RateLog
from ._designated_and import AND_DONE, AND_JOIN, AND_PUT, AndSteps
from ._designated_or import OR_CLAIM, OR_JOIN, OR_PASSED, OrSteps
from ._operations import Operations
from ._questions import STEP_KNOWN, Questions
from ._step import (
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

RUN_LOST = "mover.run_lost"
LEFT = "left"  # ``[run, step, "left"]`` on DECIDED_TOPIC: the sender's run ended after ``step``


class Collectives:
    """One per node: serves the steps this node is designated for (or receives, all-to-all),
    and holds each step's decision as known here."""

    def __init__(self, node: Node, policy: Policy = "fail") -> None:
        self.node = node
        self.policy = policy  # for runs not given their own (:meth:`set_policy`)
        self._policies: dict[str, Policy] = {}  # run -> its policy, the latest STEP_MEMORY runs
        self._steps: dict[tuple[str, int], Step] = {}
        self.operations = Operations()  # this member's, for the designated one's or_passed
        self._faults = RateLog(node.name, log)
        self._owners: asyncio.TaskGroup | None = None  # owns each served step's own group
        self._closed = False
        self._gone: set[str] = set()  # members lost (past the grace) and not back since
        self._dropped: dict[str, set[str]] = {}  # run -> members lost or left out in it
        self._through: dict[str, int] = {}  # run -> the last step this member got through
        self._left: dict[str, dict[str, int]] = {}  # run -> member whose run ended -> its last
        self._announcements = node.subscribe(DECIDED_TOPIC)
        self.questions = Questions(self)  # what a served step asks its members
        self.ors = OrSteps(self)  # the OR steps served here
        self.ands = AndSteps(self)  # the AND steps served here
        self._listener = asyncio.get_running_loop().create_task(self._serve())
        #: The procedures, by their wire name: exported, and called directly by this node's
        #: own member when it is the designated one (no message).
        self.procedures: dict[str, Callable[..., Any]] = {
            OR_JOIN: self.ors.join,
            OR_CLAIM: self.ors.claim,
            OR_PASSED: self.operations.or_passed,
            STEP_KNOWN: self.step_known,
            AND_DONE: self.ands.done,
            AND_JOIN: self.ands.join,
            AND_PUT: self.ands.put,
            RUN_LOST: self.run_lost,
        }
        for name, procedure in self.procedures.items():
            node.export(procedure, name)
        # Only a member gone for LOST_GRACE counts as lost: when a router restarts, every
        # member sees the others leave a moment before it sees its own link go.
        node.membership.on_leave(self._gone.discard)  # lost again only after the grace
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

    def decision(self, run: str, step: int) -> asyncio.Future[Decision]:
        """The decision of step ``(run, step)`` once known here (a future; read only)."""
        return self._record(run, step).decision

    def learned(self, run: str, step: int, decision: Decision) -> None:
        """This node's member learned the decision of step ``(run, step)`` in an answer: it
        is known here now, as if heard (should this node become the designated member of an
        OR, it hands the decision on; asked :meth:`run_lost`, it answers from it)."""
        state = self._record(run, step)
        if not state.decision.done():
            self._decide(state, decision)

    def _decide(self, state: Step, decision: Decision) -> None:
        """The one writer of a step's decision (decided here, heard, or learned)."""
        state.decision.set_result(decision)
        left_out = set(decision.lost)
        if decision.kind == "all" and state.served:
            left_out |= state.members - decision.results.keys()  # survivors: dropped
        if left_out:
            self._dropped.setdefault(state.run, set()).update(left_out)
            while len(self._dropped) > STEP_MEMORY:
                del self._dropped[next(iter(self._dropped))]
        if state.served:
            self.ors.tell(state)

    def run_lost(self, run: str) -> list[str]:
        """The members of run ``run`` that a step decided here, heard or learned here lost
        (policy ``fail``) or left out (``survivors``): asked by a member back from a stall,
        which cannot tell otherwise whether the team went on without it."""
        return sorted(self._dropped.get(run, ()))

    def step_known(self, run: str, step: int) -> Any:
        """A successor taking step ``(run, step)`` over asks what this node knows of it: its
        decision if known here (as on the wire), else None, at once. A member that knows
        nothing cannot learn the decision but from the successor (the member that made it is
        gone): it joins the successor once it reaches the step, if it ever does (not if its run
        ended here), and gets the successor's."""
        state = self._steps.get((run, step))
        known = None if state is None else state.decision
        if known is None or not known.done() or known.cancelled() or known.exception():
            return None
        return known.result().to_wire()

    def serve(self, run: str, step: int, members: Sequence[str], kind: str = "and") -> Step:
        """The record of step ``(run, step)``, served here as its designated member (or, for an
        all-to-all AND, as one of its receivers)."""
        state = self._record(run, step)
        if not state.served:
            state.served, state.kind, state.members = True, kind, frozenset(members)
            name, alive = self.node.name, self.node.membership
            state.lost = [m for m in members if m < name and m not in alive]
            # (an all-to-all AND has no designated member: each receiver counts for itself)
            state.takeover = bool(state.lost) and kind != "and_all"
            # Lost before the step was served here (before any member reached it, say): as
            # if lost during it (_member_left), or no one would ever count it.
            state.gone = {m for m in state.members & self._gone if m not in alive}
            # Its run ended here before the step (it said so): as if lost, too.
            state.gone |= {m for m in state.members if self._ended_before(run, m, step)}
        return state

    def sent(self, run: str, step: int) -> int:
        """Messages OR step ``(run, step)`` cost from here as its designated member: the
        announcement's deliveries and the ``or_passed`` questions with their answers."""
        state = self._steps.get((run, step))
        return 0 if state is None else state.announced + 2 * state.questions

    async def _serve(self) -> None:
        """Hear the announcements, and own the served steps' groups (until the node closes:
        their questions are then cancelled, as nobody is left to tell their answers to)."""
        async with asyncio.TaskGroup() as owners:
            self._owners = owners
            try:
                await self._listen()
            finally:
                self._closed, self._owners = True, None

    async def _own(self, state: Step) -> None:
        """The owner of served step ``state``'s tasks (its or_passed questions): a TaskGroup
        that ends, its tasks cancelled and awaited, once the step is decided."""
        async with asyncio.TaskGroup() as group:
            state.tasks = group
            state.owned.set_result(None)
            await asyncio.wait({state.decision})
            for task in state.asking.values():
                task.cancel()
        state.tasks = None

    def _start_owner(self, state: Step) -> None:
        """Start ``state``'s owner, once (not before the node's group is, nor once decided)."""
        if state.owner is None and self._owners is not None and not state.decision.done():
            state.owner = self._owners.create_task(self._own(state))

    async def _owned(self, state: Step) -> None:
        """Start ``state``'s owner (once), and return once it owns the step's tasks."""
        self._start_owner(state)
        if state.owner is not None:
            await asyncio.wait({state.owned, state.owner}, return_when=asyncio.FIRST_COMPLETED)

    async def step_ended(self, run: str, step: int) -> None:
        """Once every task step ``(run, step)`` started here has ended (its decision known)."""
        state = self._steps.get((run, step))
        if state is not None and state.owner is not None:
            await asyncio.wait({state.owner})

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
                if data[2] == LEFT:
                    if message.sender in self.node.membership:  # (a live member only)
                        self._member_ended(data[0], message.sender, data[1])
                    continue
                decision = Decision.from_wire(data[2])
            except WireError as exc:
                self._faults.warn("decision", f"dropped a decision from {message.sender!r}: {exc}")
                continue
            state = self._record(data[0], data[1])
            if not state.decision.done():
                self._decide(state, decision)  # heard: another member decided it

    def start_run(self, run: str) -> None:
        """A run named ``run`` starts here: forget what an earlier run of that name left (its
        decided steps, heard decisions, operations, whom it lost, whose run ended; that it
        ended). What other members already sent for the new run stays: it cannot be decided
        before this member began."""
        self.operations.start_run(run)
        self._dropped.pop(run, None)
        self._through.pop(run, None)
        self._left.pop(run, None)
        for key in [k for k, st in self._steps.items() if k[0] == run and st.decision.done()]:
            del self._steps[key]

    def set_policy(self, run: str, policy: Policy) -> None:
        """Run ``run``'s steps follow ``policy`` (every member of it is started with the same)."""
        self._policies[run] = policy
        while len(self._policies) > STEP_MEMORY:
            del self._policies[next(iter(self._policies))]

    def policy_of(self, run: str) -> Policy:
        """The policy of run ``run``'s steps."""
        return self._policies.get(run, self.policy)

    def _fails(self, state: Step) -> bool:
        """Whether a lost member fails ``state``'s step (policy ``fail``)."""
        return self.policy_of(state.run) == "fail"

    def _lost_in(self, state: Step) -> tuple[str, ...]:
        """The members whose loss fails ``state``'s step (policy ``fail``; else none): the
        designated members before this one (taking over) and those lost since, but for an
        all-to-all AND's members whose result is in (they may have finished and left)."""
        if not self._fails(state):
            return ()
        spared = state.results.keys() if state.kind == "and_all" else set()
        return tuple(sorted(set(state.lost) | (state.gone - spared)))

    def _expected(self, state: Step) -> set[str]:
        """The members whose word the step waits for: those alive, but for those an earlier
        step of the run went on without (``survivors``: one back from a stall is not waited
        for again, as its run ends when it sees the team: ProgramHost) and those whose run
        ended before the step."""
        dropped = self._dropped.get(state.run, set())
        return {
            m
            for m in state.members
            if m in self.node.membership
            and m not in dropped
            and not self._ended_before(state.run, m, state.step)
        }

    def got_through(self, run: str, step: int) -> None:
        """This node's member got through step ``(run, step)`` (its decision known here)."""
        self._through[run] = step
        while len(self._through) > STEP_MEMORY:
            del self._through[next(iter(self._through))]

    def end_run(self, run: str) -> None:
        """Run ``run`` ended here (its program returned, raised or was cancelled): questions
        about its steps are answered "out" from now on, and the run's other members are told
        (one broadcast, ``[run, step, "left"]``) that this member takes part in none of its
        steps after ``step``, the last it got through: one that waits for it ends as if it
        had been lost (:meth:`_member_ended`), here too."""
        self.operations.end_run(run)
        through = self._through.pop(run, 0)
        self._member_ended(run, self.node.name, through)
        if not self._closed:
            try:
                self.node.broadcast_nowait(DECIDED_TOPIC, [run, through, LEFT], reliable=True)
            except MoverError as exc:  # the node is closing: its members see it go
                log.debug("%s: run %r ended unannounced: %s", self.node.name, run, exc)

    def _ended_before(self, run: str, member: str, step: int) -> bool:
        """Whether ``member``'s run ``run`` ended before step ``step`` (as it said)."""
        return self._left.get(run, {}).get(member, step) < step

    def _member_ended(self, run: str, member: str, through: int) -> None:
        """``member``'s run ``run`` ended after its step ``through``: every later step of the
        run served here counts it as gone (policy ``fail``: lost; ``survivors``: not waited
        for), whether served already or later (:meth:`serve`)."""
        self._left.setdefault(run, {})[member] = through
        while len(self._left) > STEP_MEMORY:
            del self._left[next(iter(self._left))]
        for state in list(self._steps.values()):
            if state.run == run and state.step > through:
                self._count_gone(state, member)

    def _settle(self, state: Step) -> None:
        """Decide served step ``state`` if it can be, now."""
        (self.ors if state.kind == "or" else self.ands).settle(state)

    def _member_left(self, name: str) -> None:
        if not self.node.connected():
            return  # we are cut off, not they: stall (see docs/collectives.md, Failures)
        self._gone.add(name)  # for the steps served from now on, too
        for state in list(self._steps.values()):
            self._count_gone(state, name, takeover=name < self.node.name)

    def _count_gone(self, state: Step, name: str, *, takeover: bool = False) -> None:
        """Member ``name`` is gone from step ``state``: if this node serves it, undecided,
        decide it if it can be, now (``takeover``: it may have been the designated member)."""
        if not state.served or state.decision.done() or name not in state.members:
            return
        state.gone.add(name)
        if takeover and state.kind != "and_all":
            state.takeover = True  # it may have been the designated member, and decided
        if not self._expected(state):
            self._decide(state, Decision("lost", lost=tuple(sorted(state.members))))
        else:
            self._settle(state)
