"""Aseba Playground for the Thymio tests: skipped, naming the package, when it is not installed."""

from __future__ import annotations

import asyncio
import re
from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from pathlib import Path

import pytest
import pytest_asyncio

from mover._config import free_port
from robots.thymio.playground import playground_command, start_playground, stop_playground

ROOT = Path(__file__).resolve().parents[2]

needs_playground = pytest.mark.skipif(
    playground_command() is None,
    reason="asebaplayground is not installed (Debian package: aseba)",
)


def shipped_world(tmp_path: Path) -> tuple[Path, list[int]]:
    """A copy of worlds/thymio_gather.playground (and its floor) on free ports; the ports."""
    text = (ROOT / "worlds" / "thymio_gather.playground").read_text()
    ports = [free_port() for _ in re.findall(r'port="(\d+)"', text)]
    for old, new in zip(re.findall(r'port="(\d+)"', text), ports, strict=True):
        text = text.replace(f'port="{old}"', f'port="{new}"')
    (tmp_path / "thymio_gather.png").write_bytes(
        (ROOT / "worlds" / "thymio_gather.png").read_bytes()
    )
    world = tmp_path / "thymio_gather.playground"
    world.write_text(text)
    return world, ports


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
