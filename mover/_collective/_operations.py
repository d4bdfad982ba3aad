"""This member's OR operations, for the designated member's ``or_passed`` questions.

A member answers whether its operation of a step finished, or its clock went past a time,
from here; the designated member (:class:`~._designated.Collectives`) asks. Kept apart from
both sides because the question can come before this member reached the step (it waits here),
and after its run ended (answered "out"). Memory: the last ``STEP_MEMORY`` steps and runs.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import deque
from typing import Any

from ._clock import TimedOp
from ._step import STEP_MEMORY


class Operations:
    """This node's OR operations, by step, once reached (None: not timed)."""

    def __init__(self) -> None:
        self._local: dict[tuple[str, int], asyncio.Future[TimedOp | None]] = {}
        self._ended: deque[str] = deque(maxlen=STEP_MEMORY)  # runs that ended here

    def _reaching(self, run: str, step: int) -> asyncio.Future[TimedOp | None]:
        future = self._local.get((run, step))
        if future is None:
            future = self._local[(run, step)] = asyncio.get_running_loop().create_future()
            while len(self._local) > STEP_MEMORY:
                old = self._local.pop(next(iter(self._local)))
                if not old.done():
                    old.set_result(None)
        return future

    def reached(self, run: str, step: int, local: TimedOp | None) -> None:
        """This member started its operation of OR step ``(run, step)`` (None: untimed)."""
        future = self._reaching(run, step)
        if not future.done():
            future.set_result(local)

    def start_run(self, run: str) -> None:
        """A run named ``run`` starts here: forget an earlier run's operations of that name."""
        with contextlib.suppress(ValueError):
            self._ended.remove(run)
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
