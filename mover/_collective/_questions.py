"""The questions a node serving a step asks its members: :class:`Questions`.

The designated member of a timed OR asks ``or_passed`` (:class:`~._designated_or.OrSteps`); a
successor taking a step over from a designated member that is gone first asks every live
member ``step_known`` (:meth:`Questions.heard_all`): the gone one may have decided the step and
told some members before it died, and a decision once made is the one every member ends with,
so a successor decides only once every live member has said what it knows, and adopts a
decision one of them holds. A question runs in the step's own TaskGroup (it ends, awaited, when
the step is decided), one at a time per (question, member), asked again while the member lives.
Costs: two messages a question (``Step.questions``; ``docs/collectives.md``).
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Awaitable, Callable
from functools import partial
from typing import TYPE_CHECKING, Any

from .._exceptions import Answered, CallTimeout, NotDelivered, RemoteError, WireError
from ._reach import wait_reachable
from ._step import CALL_TIMEOUT, Decision, Step

if TYPE_CHECKING:
    from ._designated import Collectives

log = logging.getLogger("mover.tasks")

STEP_KNOWN = "mover.step_known"


class Questions:
    """The questions of the steps ``collectives`` serves (a part of it)."""

    def __init__(self, collectives: Collectives) -> None:
        self._c = collectives

    def ask(self, state: Step, key: tuple[str, str], ask: Callable[[], Awaitable[None]]) -> None:
        """Start question ``key`` (what, whom) of served step ``state``, in its group."""
        c = self._c
        task = state.asking.get(key)
        if task is not None and not task.done():
            return  # one question at a time: a later answer covers an earlier one
        if state.tasks is None:  # its owner is not (or no longer) under way
            if not c._closed and not state.decision.done():
                c._start_owner(state)  # (its group opens with a later loop turn)
                asyncio.get_running_loop().call_soon(self.ask, state, key, ask)
            return
        if c._closed or state.decision.done():
            return  # nobody is left to tell the answer to, or it is no longer needed
        question = self._question(key, ask)
        try:
            state.asking[key] = state.tasks.create_task(question)
        except RuntimeError:  # the owner's group is shutting down (the node is closing)
            question.close()

    async def _question(self, key: tuple[str, str], ask: Callable[[], Awaitable[None]]) -> None:
        try:
            await ask()
        except Exception as exc:  # a question that fails is not the other questions' concern
            log.debug("%s: %s question to %s failed: %r", self._c.node.name, *key, exc)

    async def answer(self, state: Step, member: str, procedure: str, *args: Any) -> Any:
        """``member``'s answer to ``procedure(run, step, *args)`` about ``state`` (asked again
        while it is alive); raise LookupError once it is gone (the loss then decides)."""
        node = self._c.node
        while True:
            try:
                if member == node.name:
                    answer = self._c.procedures[procedure](state.run, state.step, *args)
                    return await answer if inspect.isawaitable(answer) else answer
                state.questions += 1
                return await node.call(
                    member, procedure, state.run, state.step, *args, timeout=CALL_TIMEOUT
                )
            except CallTimeout:
                continue  # it is alive (liveness ends the call sooner): ask again
            except (NotDelivered, RemoteError) as exc:
                if isinstance(exc, RemoteError) and exc.remote_type != "Cancelled":
                    raise
                if not await wait_reachable(node, member):
                    raise LookupError(member) from None
                # lost for a moment, or its call was cancelled as it closed: ask again

    def heard_all(self, state: Step) -> bool:
        """Whether served step ``state`` may be decided here: yes as its designated member;
        taking it over (a designated member before this one is gone), only once every live
        member has said what it knows, asked ``step_known`` meanwhile. The gone one may have
        decided and told some of them: that decision is then adopted (:meth:`_known_from`)."""
        if not state.takeover:
            return True
        silent = self._c._expected(state) - state.joined - state.results.keys() - state.said
        for member in sorted(silent):
            self.ask(state, ("step_known", member), partial(self._known_from, state, member))
        return not silent

    async def _known_from(self, state: Step, member: str) -> None:
        c = self._c
        try:
            answer = await self.answer(state, member, STEP_KNOWN)
        except LookupError:
            return  # gone: the loss decides, as for any step
        except Answered as exc:  # it answers, but cannot say (a bug): it cannot know better
            log.warning("%s: %s cannot say what it knows: %s", c.node.name, member, exc)
            answer = None
        if answer is not None and not state.decision.done():
            try:
                c._decide(state, Decision.from_wire(answer))  # the one decision: adopted
                return
            except WireError as exc:
                c._faults.warn("known", f"{member!r} said no decision: {exc}")
        state.said.add(member)
        c._settle(state)
