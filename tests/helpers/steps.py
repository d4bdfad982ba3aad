"""How the collectives' tests end a step that lost a member: the one check of its policy."""

from __future__ import annotations

import asyncio
from collections.abc import Sequence
from typing import TypeVar

import pytest

from mover import MemberLost

T = TypeVar("T")


async def after_a_loss(policy: str, tasks: Sequence[asyncio.Future[T]], timeout: float) -> list[T]:
    """Await the remaining members' steps: under ``fail`` each must raise
    :class:`mover.MemberLost` (and the list is empty), else their outcomes, in order. Each gets
    ``timeout`` seconds."""
    if policy == "fail":
        for task in tasks:
            with pytest.raises(MemberLost):
                await asyncio.wait_for(task, timeout)
        return []
    return [await asyncio.wait_for(task, timeout) for task in tasks]
