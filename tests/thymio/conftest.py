"""Aseba Playground for the Thymio tests: skipped, naming the package, when it is not installed."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from pathlib import Path

import pytest
import pytest_asyncio

from mover._config import free_port
from mover._up._playground import world_robots
from robots.thymio.playground import (
    on_ports,
    playground_command,
    start_playground,
    stop_playground,
)

ROOT = Path(__file__).resolve().parents[2]

needs_playground = pytest.mark.skipif(
    playground_command() is None,
    reason="asebaplayground is not installed (Debian package: aseba)",
)


def shipped_world(tmp_path: Path) -> tuple[Path, list[int]]:
    """A copy of worlds/thymio_gather.playground (its floor linked) on free ports; the ports."""
    world = ROOT / "worlds" / "thymio_gather.playground"
    ports = {name: free_port() for name in world_robots(world.read_text())}
    return on_ports(world, ports, tmp_path), list(ports.values())


Playground = Callable[[Path, Sequence[int]], Awaitable[asyncio.subprocess.Process]]
"""``await playground(world, ports)``: the Playground started on ``world``, ready."""


@pytest_asyncio.fixture
async def playground(tmp_path: Path) -> AsyncIterator[Playground]:
    """``await playground(world, ports)``: the Playground on ``world``, ready; stopped after."""
    started = []
    log = open(tmp_path / "playground.log", "ab")  # noqa: ASYNC230, SIM115

    async def start(world: Path, ports: Sequence[int]) -> asyncio.subprocess.Process:
        proc = await start_playground(world, ports, log=log)
        started.append(proc)
        return proc

    try:
        yield start
    finally:
        for proc in started:
            await stop_playground(proc)
        log.close()
