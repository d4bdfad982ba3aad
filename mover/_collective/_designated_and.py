"""The designated member of an AND step, and each receiver of an all-to-all one: :class:`AndSteps`.

The step is decided once every live member's result is in (``and_done``; all-to-all,
``and_put`` on every receiver); a member still in its operation that saw another lost joins
(``and_join``) to hear the decision, which fails the step unless the run's policy is
``survivors``. Protocol and costs: ``docs/collectives.md``.
"""

from __future__ import annotations

from typing import Any

from ._served import ServedSteps
from ._step import Decision, Step

AND_DONE = "mover.and_done"
AND_JOIN = "mover.and_join"
AND_PUT = "mover.and_put"


class AndSteps(ServedSteps):
    """The AND steps ``collectives`` serves (a part of it)."""

    kind = "and"

    async def done(self, run: str, step: int, member: str, members: list[str], result: Any) -> Any:
        """A member finished: record its result; answer when every live member has."""
        state = self._c.serve(run, step, members)
        state.results[member] = result
        return await self._answer(state)

    def put(self, run: str, step: int, member: str, members: list[str], result: Any) -> None:
        """All-to-all: a member's result, sent to every other member."""
        state = self._c.serve(run, step, members, "and_all")
        state.results[member] = result
        self.settle(state)

    def settle(self, state: Step) -> None:
        """Decide served AND step ``state`` if it can be, now."""
        c = self._c
        if state.decision.done() or not self._may_decide(state):
            return
        expected = c._expected(state) | state.results.keys() & state.members
        if c._fails(state) and not state.members <= expected:
            return  # the loss decides the failure (Collectives._member_left)
        if expected and expected <= state.results.keys():
            results = {m: state.results[m] for m in sorted(expected)}
            c._decide(state, Decision("all", results=results))
