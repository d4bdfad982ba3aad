"""Fixtures shared by the core's tests."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest_asyncio

from mover import Node
from tests.helpers.loopback import team_nodes


@pytest_asyncio.fixture
async def nodes() -> AsyncIterator[list[Node]]:
    """Five nodes of one team in this process, n0 listening, the others connected to it, each
    seeing all five."""
    async with team_nodes([f"n{i}" for i in range(5)]) as out:
        yield out
