"""Helpers for the library and program tests: the demo world, in-process robots, a team."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Awaitable, Callable, Mapping, Sequence
from contextlib import AsyncExitStack
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio

from mover import Node, NodeConfig, TeamCredentials
from mover._config import free_port
from robots import Robot
from sim_hw import World, WorldServer, WorldSpec, in_process, load_world

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "worlds" / "search_and_rescue.toml"
NAMES = ("elvis", "ernst", "moseley")

Mesh = Callable[[Sequence[str]], Awaitable[list[Node]]]
"""The type of the ``mesh`` fixture: make nodes of one team by name."""


@pytest.fixture
def demo() -> WorldSpec:
    """The search-and-rescue demo world."""
    return load_world(DEMO)


async def robots_in(
    world: World, settings: Mapping[str, Mapping[str, Any] | None], **kwargs: Any
) -> tuple[WorldServer, dict[str, Robot]]:
    """A lock-step server over ``world`` and a Robot (no node) for each id → settings."""
    server = WorldServer(world, expect=len(settings), **kwargs)
    hws = await asyncio.gather(*(in_process(server, rid, spec) for rid, spec in settings.items()))
    return server, {rid: Robot(rid, hw) for rid, hw in zip(settings, hws, strict=True)}


async def together(
    jobs: dict[str, Callable[[], Awaitable[Any]]], robots: dict[str, Robot]
) -> dict[str, Any]:
    """Run one job per robot; a robot whose job is done keeps ticking (lock-step) until all
    are done."""
    everyone = asyncio.Event()
    left = [len(jobs)]

    async def one(rid: str) -> Any:
        try:
            return await jobs[rid]()
        finally:
            left[0] -= 1
            if left[0] == 0:
                everyone.set()
            else:
                async with robots[rid].hw.clock.ticking():
                    await everyone.wait()

    results = await asyncio.gather(*(one(rid) for rid in jobs))
    return dict(zip(jobs, results, strict=True))


@pytest_asyncio.fixture
async def mesh() -> AsyncIterator[Mesh]:
    """Make nodes of one team over zenoh on loopback (no scouting), all in this process."""
    async with AsyncExitStack() as stack:
        team = TeamCredentials.generate("rescue")

        async def make(names: Sequence[str]) -> list[Node]:
            port = free_port()
            first = await stack.enter_async_context(
                Node(names[0], team, config=NodeConfig(listen=(f"tcp/127.0.0.1:{port}",)))
            )
            out = [first]
            for name in names[1:]:
                out.append(
                    await stack.enter_async_context(
                        Node(name, team, config=NodeConfig(connect=(f"tcp/127.0.0.1:{port}",)))
                    )
                )
            for n in out:
                await n.membership.wait_for(set(names), timeout=10)
            return out

        yield make
