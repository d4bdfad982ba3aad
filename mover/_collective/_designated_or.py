"""The designated member of an OR step: :class:`OrSteps`.

The first claim wins; with simulated finish times (``or_claim``'s ``finished_at``), the earliest
does, once every live member claimed or said (``or_passed``) it went past that time. The
decision is announced at once, in one broadcast, unless every other member asked (they get it
in their answer). Protocol and costs: ``docs/collectives.md``.
"""

from __future__ import annotations

import logging
import math
from functools import partial
from typing import Any

from .._exceptions import Answered
from ._served import ServedSteps
from ._step import DECIDED_TOPIC, Decision, Step

log = logging.getLogger("mover.tasks")

OR_JOIN = "mover.or_join"
OR_CLAIM = "mover.or_claim"
OR_PASSED = "mover.or_passed"


class OrSteps(ServedSteps):
    """The OR steps ``collectives`` serves as their designated member (a part of it)."""

    kind = "or"

    async def claim(
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
        state = self._c.serve(run, step, members, "or")
        state.joined.add(member)
        if finished_at is not None:
            state.timed = True
            await self._c._owned(state)  # the questions it may ask belong to the step
        if all(m != member for m, _, _ in state.claims):
            state.claims.append((member, result, finished_at))
        return await self._answer(state)

    def tell(self, state: Step) -> None:
        """A served OR step is decided: stop asking, and tell the members the decision, in one
        broadcast unless every one of them asked (they get it in their answer). Once."""
        if state.kind != "or" or state.told:
            return
        state.told = True  # (the step's questions end with it: Collectives._own)
        node = self._c.node
        others = state.members - {node.name}
        if not others <= state.joined:
            wire = [state.run, state.step, state.decision.result().to_wire()]
            node.broadcast_nowait(DECIDED_TOPIC, wire, reliable=True)
            state.announced = len(others)

    def settle(self, state: Step) -> None:
        """Decide served OR step ``state`` if it can be, now."""
        c = self._c
        if state.decision.done():
            # Known before this node served the step (heard, or told as a member): a
            # successor hands that decision on, since the members that moved on with it
            # will never ask.
            self.tell(state)
            return
        if not self._may_decide(state):
            return
        if not state.claims:
            return
        if state.timed:
            self._settle_timed(state)
            return
        winner, result, _ = state.claims[0]
        c._decide(state, Decision("won", winner=winner, result=result))

    def _settle_timed(self, state: Step) -> None:
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
            self._c._decide(state, Decision("won", winner=winner, result=result))
            return
        for member in pending:
            # a member that finished in time: its claim is coming; one that is gone cannot say
            if member not in state.finished and member in self._c.node.membership:
                self._ask_passed(state, member, at)

    def _ask_passed(self, state: Step, member: str, t: float) -> None:
        ask = partial(self._passed_from, state, member, t)
        self._c.questions.ask(state, ("or_passed", member), ask)

    async def _passed_from(self, state: Step, member: str, t: float) -> None:
        try:
            answer = await self._c.questions.answer(state, member, OR_PASSED, t)
        except LookupError:
            return  # gone: the loss decides, as for any step
        except Answered as exc:  # it answers, but cannot say its time (no clock, a bug)
            log.warning("%s: %s cannot say its time: %s", self._c.node.name, member, exc)
            answer = {"out": True}  # it never claims
        if not isinstance(answer, dict):
            answer = {"out": True}
        finished = answer.get("finished")
        if isinstance(finished, (int, float)):
            state.finished[member] = float(finished)
        elif "passed" in answer:
            state.beyond[member] = max(t, state.beyond.get(member, -math.inf))
        else:
            state.beyond[member] = math.inf
        self.settle(state)
