"""What a collective step is: its constants, its decision (and how it travels), what a member
gets from it (outcome, results, metrics), and the state a node keeps of it.

Shared by both sides of a step; it holds data and no behaviour, so that either side reads the
same words (the protocol: ``docs/collectives.md``).
"""

from __future__ import annotations

import asyncio
import hashlib
import time
from dataclasses import dataclass, field
from typing import Any, Literal

from .._exceptions import WireError

Policy = Literal["fail", "survivors"]
POLICIES: tuple[Policy, ...] = ("fail", "survivors")

STEP_MEMORY = 512  # steps a node remembers (for late re-sends and announcements)
DECIDED_TOPIC = "mover/decided"
LOST_GRACE = 0.5  # seconds a member must stay gone (while this node is linked) to be lost
CALL_TIMEOUT = 30.0  # seconds a collective's call waits before it is asked again
POLL_AFTER = 0.2  # seconds an OR member waits for the announced decision before polling
SEED_LIMIT = 2**63  # seeds are 0 <= seed < SEED_LIMIT (they travel as msgpack integers)


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

    def to_wire(self) -> list[str]:
        """As it travels in an AND's results."""
        return ["__failed__", self.type, self.message]


def unwire(value: Any) -> Any:
    """An AND result as sent: an :class:`OperationFailed` back from its wire form."""
    if isinstance(value, list) and len(value) == 3 and value[0] == "__failed__":
        return OperationFailed(str(value[1]), str(value[2]))
    return value


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


def _future() -> asyncio.Future[Decision]:
    return asyncio.get_running_loop().create_future()


def _owned() -> asyncio.Future[None]:
    return asyncio.get_running_loop().create_future()


@dataclass
class Step:
    """What a node knows of step ``(run, step)``: its decision, once known here (decided here,
    announced, or told in an answer), and, once the node serves the step as its designated
    member (``served``), what it has heard from the members. Written only by the node's
    :class:`~mover._collective._designated.Collectives` and its parts."""

    run: str
    step: int
    decision: asyncio.Future[Decision] = field(default_factory=_future)
    served: bool = False  # this node serves the step as its designated member (or all-to-all)
    kind: str = "and"  # "or", "and", or "and_all" (an all-to-all AND's receiver)
    members: frozenset[str] = frozenset()
    joined: set[str] = field(default_factory=set)
    claims: list[tuple[str, Any, float | None]] = field(default_factory=list)
    results: dict[str, Any] = field(default_factory=dict)
    takeover: bool = False  # this member took over from a designated member that is gone
    lost: list[str] = field(default_factory=list)  # members already gone when it took over
    announced: int = 0  # deliveries of the OR decision's broadcast (n-1, or 0 if none was sent)
    told: bool = False  # the OR decision was announced (or needed no announcement)
    timed: bool = False  # an OR decided in simulated time (its claims carry finish times)
    beyond: dict[str, float] = field(default_factory=dict)  # member: a time it went past
    finished: dict[str, float] = field(default_factory=dict)  # member: its answered finish
    # (question, member): a question under way (or_passed; step_known, taking the step over)
    asking: dict[tuple[str, str], asyncio.Task[None]] = field(default_factory=dict)
    owner: asyncio.Task[None] | None = None  # owns the step's tasks until it is decided
    owned: asyncio.Future[None] = field(default_factory=_owned)  # the owner's group is open
    tasks: asyncio.TaskGroup | None = None  # the owner's group (the step's questions)
    questions: int = 0  # or_passed and step_known calls sent from here (two messages each)
    gone: set[str] = field(default_factory=set)  # members lost during the step (on_gone)
    said: set[str] = field(default_factory=set)  # answered step_known: it knows nothing
