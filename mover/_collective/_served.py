"""What the OR and the AND steps served here share: :class:`ServedSteps`.

A member that asks is answered with the decision once taken; a step is decided by its kind's
rule only once every live member has said what it knows (a successor's questions), and a
member lost before then decides it at once. Protocol and costs: ``docs/collectives.md``.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any, ClassVar

from ._step import Decision, Step

if TYPE_CHECKING:
    from ._designated import Collectives


class ServedSteps:
    """The steps of one kind (``kind``, as :meth:`Collectives.serve` records it) that
    ``collectives`` serves (a part of it)."""

    kind: ClassVar[str]

    def __init__(self, collectives: Collectives) -> None:
        self._c = collectives

    async def join(self, run: str, step: int, member: str, members: list[str]) -> Any:
        """A member waits for the decision (for an AND, a member still in its operation that
        saw a member of the step lost: the decision fails the step unless the policy is
        ``survivors``)."""
        state = self._c.serve(run, step, members, self.kind)
        state.joined.add(member)
        return await self._answer(state)

    def settle(self, state: Step) -> None:
        """Decide served step ``state`` if it can be, now."""
        raise NotImplementedError

    async def _answer(self, state: Step) -> Any:
        """Settle ``state`` if it can be; then its decision, once taken, as on the wire."""
        self.settle(state)
        return (await asyncio.shield(state.decision)).to_wire()

    def _may_decide(self, state: Step) -> bool:
        """Whether the kind's rule may decide ``state`` now: every live member was heard, and
        none was lost (a loss decides the step here and now)."""
        c = self._c
        if not c.questions.heard_all(state):
            return False
        lost = c._lost_in(state)
        if lost:
            c._decide(state, Decision("lost", lost=lost))
            return False
        return True
