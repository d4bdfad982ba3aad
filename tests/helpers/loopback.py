"""Nodes of one team in this process over zenoh on 127.0.0.1: the first listens on a free
port, the others connect to it; each sees them all before the block begins."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator, Sequence
from contextlib import AsyncExitStack

from mover import Node, NodeConfig, TeamCredentials
from mover._config import free_port


@contextlib.asynccontextmanager
async def team_nodes(names: Sequence[str], team: str = "alpha") -> AsyncIterator[list[Node]]:
    """One node per name, in a new team called ``team``; closed at the end."""
    credentials = TeamCredentials.generate(team)
    port = free_port()
    async with AsyncExitStack() as stack:
        out = []
        for i, name in enumerate(names):
            where = f"tcp/127.0.0.1:{port}"
            config = NodeConfig(listen=(where,)) if i == 0 else NodeConfig(connect=(where,))
            out.append(await stack.enter_async_context(Node(name, credentials, config=config)))
        for node in out:
            await node.membership.wait_for(set(names), timeout=10)
        yield out
