"""Same commands, same run: idle phases of any wall-clock length change nothing.

The pymunk world's stepping and its sensor noise (seeded per robot id) depend only on the
sequence of commands, applied in id order; a world whose robots are all idle holds still.
"""

from __future__ import annotations

import asyncio
from typing import Any

import numpy as np

from sim_hw import World, WorldServer, in_process, random_obstacles

NOISY = {"sonar": {"noise": 0.02}, "odometry": {"trans_noise": 0.05, "drift": 0.02}}


async def _walk(hw: Any, rng: np.random.Generator, ticks: int, out: list[Any]) -> None:
    """A seeded walk that records what the robot reads each tick (pose, sonar, odometry)."""
    for _ in range(ticks):
        ranges = hw.sonar.ranges()
        turn = 1.5 if min(ranges[0], ranges[1], ranges[-1]) < 0.4 else rng.uniform(-1, 1)
        hw.drive.set_velocity(0.3, float(turn))
        await hw.clock.tick()
        out.append([hw.clock.now(), list(hw.radio.position()), ranges, hw.odometry.pose()])


async def _run(pause: float) -> dict[str, list[Any]]:
    spec = random_obstacles((6.0, 6.0), 6, np.random.default_rng(1))
    server = WorldServer(World(spec, seed=5), expect=2)
    a, b = await asyncio.gather(in_process(server, "a", NOISY), in_process(server, "b", NOISY))
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
    await server.aclose()
    return seen


async def test_idle_phases_of_any_length_give_the_same_run() -> None:
    short, long = await _run(0.0), await _run(0.4)
    assert short == long  # bit for bit: trajectories and (noisy) readings
    assert len(short["a"]) == 61 and len(short["b"]) == 81
    assert short["a"][-2][0] == short["b"][-2][0] == 8.0  # a idled for b's 20 ticks
