"""The one owner of the tasks a member starts in a step: :class:`StepTasks`, over a TaskGroup.

A step runs its operation, its polls and its all-to-all sends concurrently; owning them in one
group means that leaving the step (decided, failed or cancelled) awaits every one of them, so a
loser's ``finally`` (motors stop) has run before the member goes on. It costs a task per
operation and per outstanding call, nothing more.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Coroutine
from dataclasses import dataclass
from typing import Any


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


class StepTasks:
    """The tasks one step starts, owned by one :class:`asyncio.TaskGroup`: leaving the block
    awaits every one of them, and :meth:`cancel` first stops those still running. An error of
    the block or of a :meth:`spawn`-ed task cancels the others and is raised as itself (not as
    a group), so a step raises what the member's program expects (MemberLost, a CallError)."""

    def __init__(self) -> None:
        self._group = asyncio.TaskGroup()
        self._tasks: list[asyncio.Task[Any]] = []

    async def __aenter__(self) -> StepTasks:
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
