"""Fixtures shared by the core's tests."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import AsyncExitStack

import pytest_asyncio

from mover import Node, NodeConfig, TeamCredentials
from mover._config import free_port


@pytest_asyncio.fixture
async def nodes() -> AsyncIterator[list[Node]]:
    """Five nodes of one team in this process, n0 listening, the others connected to it, each
    seeing all five."""
    team = TeamCredentials.generate("alpha")
    port = free_port()
    async with AsyncExitStack() as stack:
        out = [
            await stack.enter_async_context(
                Node("n0", team, config=NodeConfig(listen=(f"tcp/127.0.0.1:{port}",)))
            )
        ]
        for i in range(1, 5):
            out.append(
                await stack.enter_async_context(
                    Node(f"n{i}", team, config=NodeConfig(connect=(f"tcp/127.0.0.1:{port}",)))
                )
            )
        for n in out:
            await n.membership.wait_for({f"n{i}" for i in range(5)}, timeout=10)
        yield out
