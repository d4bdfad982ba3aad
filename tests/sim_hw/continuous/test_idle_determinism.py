"""Same commands, same run: idle phases of any wall-clock length change nothing.

The pymunk world's stepping and its sensor noise (seeded per robot id) depend only on the
sequence of commands, applied in id order; a world whose robots are all idle holds still.
The same in process and over zenoh (a world node and robot nodes on 127.0.0.1, tick frames,
idle and wake calls), bit for bit.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from typing import Any

import numpy as np
import pytest

from mover import Node, NodeConfig, TeamCredentials
from mover._config import free_port
from sim_hw import World, WorldServer, in_process, random_obstacles, remote
from sim_hw._process import serve

NOISY = {"sonar": {"noise": 0.02}, "odometry": {"trans_noise": 0.05, "drift": 0.02}}


async def _walk(hw: Any, rng: np.random.Generator, ticks: int, out: list[Any]) -> None:
    """A seeded walk that records what the robot reads each tick (pose, sonar, odometry)."""
    for _ in range(ticks):
        ranges = hw.sonar.ranges()
        turn = 1.5 if min(ranges[0], ranges[1], ranges[-1]) < 0.4 else rng.uniform(-1, 1)
        hw.drive.set_velocity(0.3, float(turn))
        await hw.clock.tick()
        out.append([hw.clock.now(), list(hw.radio.position()), ranges, hw.odometry.pose()])


@contextlib.asynccontextmanager
async def _robots(server: WorldServer, how: str) -> AsyncIterator[tuple[Any, Any]]:
    """Robots ``a`` and ``b`` of ``server``, in process or over zenoh (``how``)."""
    if how == "in_process":
        yield await asyncio.gather(in_process(server, "a", NOISY), in_process(server, "b", NOISY))
        return
    port = free_port()
    seed = NodeConfig(listen=(f"tcp/127.0.0.1:{port}",))
    peer = NodeConfig(connect=(f"tcp/127.0.0.1:{port}",))
    team = TeamCredentials.generate("idle")
    async with contextlib.AsyncExitStack() as stack:
        world = await stack.enter_async_context(Node("world", team, kind="world", config=seed))
        a, b = [await stack.enter_async_context(Node(n, team, config=peer)) for n in "ab"]
        serve(world, server.door)
        await world.membership.wait_for({"world", "a", "b"}, timeout=10)
        yield await asyncio.gather(remote(a, "a", NOISY), remote(b, "b", NOISY))


async def _run(pause: float, how: str = "in_process") -> dict[str, list[Any]]:
    spec = random_obstacles((6.0, 6.0), 6, np.random.default_rng(1))
    server = WorldServer(World(spec, seed=5), expect=2)
    async with _robots(server, how) as (a, b):
        return await _walk_with_idling(server, a, b, pause)


async def _walk_with_idling(
    server: WorldServer, a: Any, b: Any, pause: float
) -> dict[str, list[Any]]:
    ra, rb = np.random.default_rng(10), np.random.default_rng(11)
    seen: dict[str, list[Any]] = {"a": [], "b": []}
    a_idle, b_back, over = asyncio.Event(), asyncio.Event(), asyncio.Event()
    # Both are awake before either ticks again (as a run's members pass a barrier after they
    # engage their clocks): else the first awake would tick the world alone for a while.
    begin = asyncio.Barrier(2)

    async def first() -> None:
        await _walk(a, ra, 30, seen["a"])
        async with a.clock.idling():  # b goes on alone, then both are idle for ``pause``
            a_idle.set()
            await b_back.wait()
        await begin.wait()
        await _walk(a, ra, 30, seen["a"])
        async with a.clock.idling():  # done: the world must not wait for a
            await over.wait()

    async def second() -> None:
        await _walk(b, rb, 30, seen["b"])
        await a_idle.wait()
        await _walk(b, rb, 20, seen["b"])
        async with b.clock.idling():
            await asyncio.sleep(pause)  # everyone idle: the world holds still
            b_back.set()
        await begin.wait()
        await _walk(b, rb, 30, seen["b"])
        over.set()

    await asyncio.wait_for(asyncio.gather(first(), second()), 30)
    seen["a"].append(server.world.readings("a"))
    seen["b"].append(server.world.readings("b"))
    await server.door.aclose()
    return seen


async def test_idle_phases_of_any_length_give_the_same_run() -> None:
    short, long = await _run(0.0), await _run(0.4)
    assert short == long  # bit for bit: trajectories and (noisy) readings
    assert len(short["a"]) == 61 and len(short["b"]) == 81
    assert short["a"][-2][0] == short["b"][-2][0] == 8.0  # a idled for b's 20 ticks


@pytest.mark.timeout(60)
async def test_over_zenoh_the_same_run_as_in_process() -> None:
    local = await _run(0.0)
    assert await _run(0.3, "remote") == local
