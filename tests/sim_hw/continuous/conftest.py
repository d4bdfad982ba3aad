"""Helpers shared by the simulated-world tests."""

from __future__ import annotations

from typing import Any

import pytest

from robots.hal import Hardware
from sim_hw import World, WorldServer, WorldSpec


@pytest.fixture
def arena() -> WorldSpec:
    """An empty 10 m × 8 m arena."""
    return WorldSpec(size=(10.0, 8.0))


async def start(
    world: World, robots: dict[str, dict[str, Any]], **kwargs: Any
) -> tuple[WorldServer, dict[str, Hardware]]:
    """A lock-step server over ``world`` and the HALs of ``robots`` (id → settings)."""
    import asyncio

    from sim_hw import in_process

    server = WorldServer(world, expect=len(robots), **kwargs)
    hws = await asyncio.gather(*(in_process(server, rid, spec) for rid, spec in robots.items()))
    return server, dict(zip(robots, hws, strict=True))
