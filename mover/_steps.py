"""What a collective step is made of: its constants, its outcome and metrics, the decision
the designated member takes, the state it keeps, and a member's operation as the designated
member sees it in simulated time (:class:`RunClock`), and the one owner of a step's tasks
(:class:`_StepTasks`). See :mod:`mover._tasks` for the protocol.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import logging
import time
from collections.abc import Awaitable, Callable, Coroutine, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol

from ._exceptions import WireError

if TYPE_CHECKING:
    from ._node import Node

log = logging.getLogger("mover.tasks")

Policy = Literal["fail", "survivors"]
POLICIES: tuple[Policy, ...] = ("fail", "survivors")

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

    def lost_message(self, run: str, step: int, me: str) -> str:
        """What a ``lost`` decision tells member ``me``: who was lost, and, if ``me`` is among
        them (it was out of reach past its lease, a frozen process say), that it was."""
        said = f"step {step} of run {run!r} lost {list(self.lost)}"
        if me in self.lost:
            said += f": this member ({me}) among them, out of the team's reach past its lease"
        return said

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


@dataclass(frozen=True, slots=True)
class Settled:
    """How a task of a step ended: its ``value``, or the ``error`` it raised (kept as data, so
    that one task's failure is its step's to judge, not its task group's)."""

    value: Any = None
    error: Exception | None = None

    def get(self) -> Any:
        """The value, or raise the error."""
        if self.error is not None:
            raise self.error
        return self.value


async def settled(awaitable: Awaitable[Any]) -> Settled:
    """``awaitable``'s outcome as a :class:`Settled` (cancellation still propagates)."""
    try:
        return Settled(await awaitable)
    except Exception as exc:
        return Settled(error=exc)


class _StepTasks:
    """The tasks one step starts (its operation, its polls, its all-to-all sends), owned by one
    :class:`asyncio.TaskGroup`: leaving the block — decided, failed or cancelled — awaits every
    one of them, and :meth:`cancel` first stops those still running. An error of the block or of
    a :meth:`spawn`-ed task cancels the others and is raised as itself (not as a group), so a
    step raises what the member's program expects (MemberLost, a CallError)."""

    def __init__(self) -> None:
        self._group = asyncio.TaskGroup()
        self._tasks: list[asyncio.Task[Any]] = []

    async def __aenter__(self) -> _StepTasks:
        await self._group.__aenter__()
        return self

    async def __aexit__(self, *exc: Any) -> None:
        try:
            await self._group.__aexit__(*exc)
        except BaseExceptionGroup as group:
            raise _first(group) from None

    def start(self, awaitable: Awaitable[Any]) -> asyncio.Task[Settled]:
        """A task whose outcome the step judges (it settles, it does not raise)."""
        task = self._group.create_task(settled(awaitable))
        self._tasks.append(task)
        return task

    def spawn(self, coroutine: Coroutine[Any, Any, Any]) -> asyncio.Task[Any]:
        """A task whose error fails the step."""
        task = self._group.create_task(coroutine)
        self._tasks.append(task)
        return task

    def cancel(self) -> None:
        """Stop the tasks still running (leaving the block then awaits their cleanup)."""
        for task in self._tasks:
            task.cancel()


def _first(group: BaseExceptionGroup[BaseException]) -> BaseException:
    error = group.exceptions[0]
    return _first(error) if isinstance(error, BaseExceptionGroup) else error


Spawn = Callable[[Awaitable[Any]], "asyncio.Task[Settled]"]


class _LocalOp:
    """This member's operation in an OR step, for the designated member's ``or_passed``; it
    runs as a task of its step (``spawn``), and settles (:class:`Settled`) rather than raise."""

    def __init__(
        self, clock: RunClock, operation: Callable[[], Awaitable[Any]], spawn: Spawn
    ) -> None:
        self.clock = clock
        self.finished_at: float | None = None  # simulated time the operation returned at
        self.op: asyncio.Task[Settled] = spawn(self._run(operation))

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
