"""The designated member's side of the collective steps: one :class:`Collectives` per node
serves the steps this node is designated for (the claims, polls and results of the others,
the decisions and their announcement), answers ``or_passed`` for its own operations, and
fails the steps of members that leave. See :mod:`mover._tasks` for the protocol."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections import deque
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from ._exceptions import (
    Answered,
    CallTimeout,
    MemberLost,
    NotDelivered,
    RemoteError,
    WireError,
)
from ._session import FaultLog
from ._steps import (
    _STEP_MEMORY,
    CALL_TIMEOUT,
    DECIDED_TOPIC,
    LOST_GRACE,
    Decision,
    Policy,
    _cancel_all,
    _LocalOp,
    _quiet,
    _Step,
    wait_reachable,
)

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.tasks")


class Collectives:
    """One per node: serves the steps this node is designated for (or receives, all-to-all)."""

    def __init__(self, node: Node, policy: Policy = "fail") -> None:
        self.node = node
        self.policy = policy  # for runs not given their own (:meth:`set_policy`)
        self._policies: dict[str, Policy] = {}  # run -> its policy, the latest _STEP_MEMORY runs
        self._steps: dict[tuple[str, int], _Step] = {}
        # OR decisions as announced by designated members (one broadcast per step)
        self._heard: dict[tuple[str, int], asyncio.Future[Decision]] = {}
        # this member's OR operations, by step, once reached (None: not timed), for or_passed
        self._local: dict[tuple[str, int], asyncio.Future[_LocalOp | None]] = {}
        self._ended: deque[str] = deque(maxlen=_STEP_MEMORY)  # runs that ended here
        self._faults = FaultLog(node.name)
        self._announcements = node.subscribe(DECIDED_TOPIC)
        self._listener = asyncio.get_running_loop().create_task(self._listen())
        node.export(self.or_join, "mover.or_join")
        node.export(self.or_claim, "mover.or_claim")
        node.export(self.or_passed, "mover.or_passed")
        node.export(self.and_done, "mover.and_done")
        node.export(self.and_put, "mover.and_put")
        # Only a member gone for LOST_GRACE counts as lost: when a router restarts, every
        # member sees the others leave a moment before it sees its own link go.
        node.team.on_gone(self._member_left, grace=LOST_GRACE)

    def step(self, run: str, step: int, members: Sequence[str], kind: str = "and") -> _Step:
        key = (run, step)
        state = self._steps.get(key)
        if state is None:
            state = self._steps[key] = _Step(frozenset(members), run, step)
            if kind == "or":
                state.decision.add_done_callback(lambda _: self._announce(run, step, state))
                state.decision.add_done_callback(lambda _: _cancel_all(state.asking))
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
                self._faults.warn(message.sender, f"dropped a decision: {exc}")
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

    def sent(self, run: str, step: int) -> int:
        """Messages OR step ``(run, step)`` cost from here as its designated member: the
        announcement's deliveries and the ``or_passed`` questions with their answers."""
        state = self._steps.get((run, step))
        return self.announced(run, step) + (2 * state.questions if state is not None else 0)

    # -- this member's operations, for a designated member's or_passed ---------------------

    def _reaching(self, run: str, step: int) -> asyncio.Future[_LocalOp | None]:
        future = self._local.get((run, step))
        if future is None:
            future = self._local[(run, step)] = asyncio.get_running_loop().create_future()
            while len(self._local) > _STEP_MEMORY:
                old = self._local.pop(next(iter(self._local)))
                if not old.done():
                    old.set_result(None)
        return future

    def reached(self, run: str, step: int, local: _LocalOp | None) -> None:
        """This member started its operation of OR step ``(run, step)`` (None: untimed)."""
        future = self._reaching(run, step)
        if not future.done():
            future.set_result(local)

    def start_run(self, run: str) -> None:
        """A run named ``run`` starts here: forget what an earlier run of that name left (its
        decided steps, heard decisions, operations; that it ended). What other members already
        sent for the new run stays: it cannot be decided before this member began."""
        with contextlib.suppress(ValueError):
            self._ended.remove(run)
        for key in [k for k, st in self._steps.items() if k[0] == run and st.decision.done()]:
            del self._steps[key]
        for key in [k for k, f in self._heard.items() if k[0] == run and f.done()]:
            del self._heard[key]
        for key in [k for k in self._local if k[0] == run]:
            future = self._local.pop(key)
            if not future.done():
                future.set_result(None)

    def set_policy(self, run: str, policy: Policy) -> None:
        """Run ``run``'s steps follow ``policy`` (every member of it is started with the same)."""
        self._policies[run] = policy
        while len(self._policies) > _STEP_MEMORY:
            del self._policies[next(iter(self._policies))]

    def _fails(self, state: _Step) -> bool:
        """Whether a lost member fails ``state``'s step (policy ``fail``)."""
        return self._policies.get(state.run, self.policy) == "fail"

    def end_run(self, run: str) -> None:
        """Run ``run`` ended here: questions about its steps are answered "out" from now on."""
        self._ended.append(run)
        for (r, _), future in list(self._local.items()):
            if r == run and not future.done():
                future.set_result(None)

    async def or_passed(self, run: str, step: int, t: float) -> dict[str, Any]:
        """The designated member asks whether this member went past simulated time ``t`` in
        OR step ``(run, step)``. Answers ``{"finished": time}`` once the operation finished (its
        claim is on its way), ``{"passed": now}`` once the clock passed ``t``, ``{"out": True}``
        if it will never claim (its operation failed, the run ended here, no clock); a member
        that has not reached the step yet answers once it has."""
        if run in self._ended:
            return {"out": True}
        local = await asyncio.shield(self._reaching(run, step))
        if local is None:
            return {"out": True}
        return await local.passed(t)

    def _ask_passed(self, state: _Step, member: str, t: float) -> None:
        task = state.asking.get(member)
        if task is None or task.done():  # one question at a time: a later answer covers an
            task = asyncio.get_running_loop().create_task(self._passed_from(state, member, t))
            task.add_done_callback(_quiet)  # earlier time, as times only go back
            state.asking[member] = task

    async def _passed_from(self, state: _Step, member: str, t: float) -> None:
        while not state.decision.done():
            try:
                if member == self.node.name:
                    answer = await self.or_passed(state.run, state.step, t)
                else:
                    state.questions += 1
                    answer = await self.node.call(
                        member, "mover.or_passed", state.run, state.step, t, timeout=CALL_TIMEOUT
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

    def _expected(self, state: _Step) -> set[str]:
        return {m for m in state.members if m in self.node.team}

    async def or_join(self, run: str, step: int, member: str, members: list[str]) -> Any:
        """A member waits for the decision."""
        state = self.step(run, step, members, "or")
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
        ``finished_at``, finished earlier in simulated time: see the module docstring)."""
        state = self.step(run, step, members, "or")
        state.joined.add(member)
        if finished_at is not None:
            state.timed = True
        if all(m != member for m, _, _ in state.claims):
            state.claims.append((member, result, finished_at))
        self._maybe_decide(state)
        return (await asyncio.shield(state.decision)).to_wire()

    def _maybe_decide(self, state: _Step) -> None:
        if state.decision.done():
            return
        if state.takeover:
            if not self._expected(state) <= state.joined:
                return  # a successor decides only once every live member has said what it knows
            if state.lost and self._fails(state):
                state.decision.set_result(Decision("lost", lost=tuple(state.lost)))
                return
        if not state.claims:
            return
        if state.timed:
            self._maybe_decide_timed(state)
            return
        winner, result, _ = state.claims[0]
        state.decision.set_result(Decision("won", winner=winner, result=result))

    def _maybe_decide_timed(self, state: _Step) -> None:
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
            state.decision.set_result(Decision("won", winner=winner, result=result))
            return
        for member in pending:
            # a member that finished in time: its claim is coming; one that is gone cannot say
            if member not in state.finished and member in self.node.team:
                self._ask_passed(state, member, at)

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
        if state.lost and self._fails(state):
            state.decision.set_result(Decision("lost", lost=tuple(state.lost)))
            return
        expected = self._expected(state) | state.results.keys() & state.members
        if self._fails(state) and not state.members <= expected:
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
            state.gone.add(name)
            alive = self._expected(state)
            if not alive:
                state.decision.set_result(Decision("lost", lost=tuple(sorted(state.members))))
            elif self._fails(state) and name not in state.results:
                state.decision.set_result(Decision("lost", lost=(name,)))
            else:
                self._maybe_decide(state)
                self._maybe_complete(state)
