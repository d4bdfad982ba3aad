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
A member waiting for the decision must keep its hardware ticking (``hw.clock.ticking()``), or a
lock-step world holds still and the others never pass the claimed time. Limitation: the losers'
operations are cancelled when the decision reaches them, on whichever tick that is in wall
time, so the winner, its result and its finish time repeat run after run, but how far the
losers went after it does not (a clock that could hold the world until the decision would fix
that).

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
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import logging
import math
import random
import time
from collections import deque
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol

from ._exceptions import (
    Answered,
    CallTimeout,
    MemberLost,
    NotDelivered,
    RemoteError,
    WireError,
)

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.tasks")

Policy = Literal["fail", "survivors"]
_STEP_MEMORY = 512  # finished steps a designated member remembers (for late re-sends)
DECIDED_TOPIC = "mover/decided"
LOST_GRACE = 0.5  # seconds a member must stay gone (while this node is linked) to be lost
CALL_TIMEOUT = 30.0  # seconds a collective's call waits before it is asked again
POLL_AFTER = 0.2  # seconds an OR member waits for the announced decision before polling
SEED_LIMIT = 2**63  # seeds are 0 <= seed < SEED_LIMIT (they travel as msgpack integers)


class RunClock(Protocol):
    """What a host's hardware offers for reproducible runs: its simulated time.

    ``ProgramHost.clock`` is one (or None: a workstation, or no hardware yet); the robot process
    sets it as an adapter over its hardware's clock and its idle task. A run engages it when it
    starts and releases it when the last run on the host ends.
    """

    def now(self) -> float:
        """Simulated time of the last readings."""
        ...

    async def passed(self, t: float) -> None:
        """Return once this robot has gone on past time ``t``: handed in a command on readings
        of time ``t`` or later (at once if it has). A robot whose program stopped at ``t``
        hands in nothing there."""
        ...

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)`` (a tick waits
        meanwhile): a ``distributed_or`` holds a member that went past the earliest finish until
        the step is decided, so that it stops on the same tick whatever the wall clock does."""
        ...

    def waiting(self) -> contextlib.AbstractAsyncContextManager[None]:
        """Idle for the block (the world neither waits for this robot nor moves it), engaged
        again on the way out: a ``distributed_and`` waits so for the other members."""
        ...

    async def engage(self) -> None:
        """Stop idling: on return the world waits for this robot's commands."""
        ...

    def release(self) -> None:
        """No run drives the hardware any more: idle again."""
        ...


def seed_of(run: str) -> int:
    """The default seed of run ``run``: derived from its name (the same name, the same seed)."""
    return int.from_bytes(hashlib.sha256(run.encode()).digest()[:4], "big")


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


class _LocalOp:
    """This member's operation in an OR step, for the designated member's ``or_passed``."""

    def __init__(self, clock: RunClock, operation: Callable[[], Awaitable[Any]]) -> None:
        self.clock = clock
        self.finished_at: float | None = None  # simulated time the operation returned at
        self.op: asyncio.Future[Any] = asyncio.ensure_future(self._run(operation))

    async def _run(self, operation: Callable[[], Awaitable[Any]]) -> Any:
        result = await operation()
        self.finished_at = self.clock.now()  # as it returns: no loop turn in between
        return result

    async def passed(self, t: float) -> dict[str, Any]:
        """Once the operation finished or the clock passed ``t``: which (see or_passed)."""
        if self.finished_at is None and not self.op.done():
            waiter = asyncio.ensure_future(self.clock.passed(t))
            try:
                await asyncio.wait({self.op, waiter}, return_when=asyncio.FIRST_COMPLETED)
            finally:
                waiter.cancel()
                await asyncio.gather(waiter, return_exceptions=True)
            lost = waiter.done() and not waiter.cancelled() and waiter.exception() is not None
            if lost and self.finished_at is None:
                return {"out": True}  # the hardware went away: this run will not claim
            for _ in range(3):  # an operation the same readings ended returns first
                if self.finished_at is not None or self.op.done():
                    break
                await asyncio.sleep(0)
        if self.finished_at is not None:
            return {"finished": self.finished_at}
        if self.op.done():
            return {"out": True}  # failed or cancelled: it will never claim
        self.clock.hold(t)  # no further until decided: where a loser stops is then fixed
        return {"passed": self.clock.now()}


@dataclass
class _Step:
    members: frozenset[str]
    run: str = ""
    step: int = 0
    joined: set[str] = field(default_factory=set)
    claims: list[tuple[str, Any, float | None]] = field(default_factory=list)
    results: dict[str, Any] = field(default_factory=dict)
    decision: asyncio.Future[Decision] = field(
        default_factory=lambda: asyncio.get_running_loop().create_future()
    )
    takeover: bool = False  # this member took over from a designated member that is gone
    lost: list[str] = field(default_factory=list)  # members already gone when it took over
    announced: int = 0  # deliveries of the OR decision's broadcast (n-1, or 0 if none was sent)
    told: bool = False  # the OR decision was announced (or needed no announcement)
    timed: bool = False  # an OR decided in simulated time (its claims carry finish times)
    beyond: dict[str, float] = field(default_factory=dict)  # member: a time it went past
    finished: dict[str, float] = field(default_factory=dict)  # member: its answered finish
    asking: dict[str, asyncio.Task[None]] = field(default_factory=dict)  # or_passed under way
    questions: int = 0  # or_passed calls sent from here (two messages each)
    gone: set[str] = field(default_factory=set)  # members lost during the step (on_gone)


class Collectives:
    """One per node: serves the steps this node is designated for (or receives, all-to-all)."""

    def __init__(self, node: Node, policy: Policy = "fail") -> None:
        self.node = node
        self.policy = policy
        self._steps: dict[tuple[str, int], _Step] = {}
        # OR decisions as announced by designated members (one broadcast per step)
        self._heard: dict[tuple[str, int], asyncio.Future[Decision]] = {}
        # this member's OR operations, by step, once reached (None: not timed), for or_passed
        self._local: dict[tuple[str, int], asyncio.Future[_LocalOp | None]] = {}
        self._ended: deque[str] = deque(maxlen=_STEP_MEMORY)  # runs that ended here
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
            if state.lost and self.policy == "fail":
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
            state.gone.add(name)
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
                f"step {metrics.step} of run {self.run!r} lost {list(decision.lost)}",
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
        local = _LocalOp(self.clock, operation) if self.clock and self.simulated else None
        op = local.op if local is not None else asyncio.ensure_future(operation())
        self.collectives.reached(self.run, metrics.step, local)
        try:
            decision = await self._or_decision(metrics, op, local)
        finally:
            if not op.done():
                op.cancel()
            if local is not None:
                local.clock.hold(None)  # after the cancel: the operation hands in nothing more
            await asyncio.gather(op, return_exceptions=True)  # the losers' cleanup runs here
        metrics.continued = time.perf_counter()
        self._raise_lost(metrics, decision)
        outcome = Outcome(decision.winner, decision.result)
        return await continuation(outcome) if continuation else outcome

    async def _or_decision(
        self, metrics: StepMetrics, op: asyncio.Future[Any], local: _LocalOp | None
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
            return await self._or_wait(metrics, op, heard, designated, local)
        finally:
            # The designated member counts its announcement's deliveries (n-1, or none), and
            # in simulated time its questions.
            metrics.messages += self.collectives.sent(self.run, metrics.step)

    async def _or_wait(
        self,
        metrics: StepMetrics,
        op: asyncio.Future[Any],
        heard: asyncio.Future[Decision],
        designated: str,
        local: _LocalOp | None,
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
                    when = () if local is None else (local.finished_at,)  # simulated time
                    answer = await self._ask(
                        metrics, designated, "mover.or_claim", *args, op.result(), *when
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
        senders = [asyncio.ensure_future(send(m)) for m in self.members if m != self.me]
        try:
            return await asyncio.shield(state.decision)
        finally:
            await asyncio.gather(*senders, return_exceptions=True)

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


def _cancel_all(tasks: dict[str, asyncio.Task[None]]) -> None:
    for task in tasks.values():
        task.cancel()


def _quiet(task: asyncio.Future[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieved: a poll nobody waits for any more may fail quietly


class _Retry(Exception):
    """A collective's call was not delivered: recover, then ask (the new designated) again."""


def _unwire(value: Any) -> Any:
    if isinstance(value, list) and len(value) == 3 and value[0] == "__failed__":
        return OperationFailed(str(value[1]), str(value[2]))
    return value
