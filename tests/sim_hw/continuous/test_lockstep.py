"""The world's clock: lock-step determinism, dropping silent robots, real time."""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Any

import numpy as np
import pytest

from robots.hal import Hardware
from sim_hw import RobotDropped, World, WorldServer, in_process, random_obstacles
from sim_hw.continuous._walker import random_walk

NOISY = {"sonar": {"noise": 0.02}, "odometry": {"trans_noise": 0.05, "drift": 0.02}}


def _ranges(hw: Hardware) -> tuple[float, ...]:
    """The robot's sonar ranges (the test worlds' robots all have a sonar)."""
    assert hw.sonar is not None
    return hw.sonar.ranges()


async def _run(
    seed: int, order: tuple[int, ...] = (2, 0, 3, 1), ticks: int = 150
) -> list[list[list[float]]]:
    robots = len(order)
    spec = random_obstacles((6.0, 6.0), 6, np.random.default_rng(1))
    server = WorldServer(World(spec, seed=seed), expect=robots)

    async def robot(i: int) -> list[list[float]]:
        hw = await in_process(server, f"r{i}", NOISY)
        return await random_walk(hw, np.random.default_rng(100 + i), ticks)

    # robots join in the given order; the world re-creates them in id order at the start
    tracks = await asyncio.gather(*(robot(i) for i in order))
    await server.door.aclose()
    return [tracks[order.index(i)] for i in range(robots)]


async def test_same_seed_same_trajectories() -> None:
    first, second = await _run(seed=5), await _run(seed=5, order=(3, 1, 0, 2))
    assert first == second  # bit for bit, whatever order the robots joined in
    assert first[0][0] != first[0][-1]  # they did move


async def test_a_silent_robot_is_dropped(caplog: pytest.LogCaptureFixture) -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2, timeout=0.2)
    live, silent = await asyncio.gather(in_process(server, "live"), in_process(server, "silent"))
    del silent  # never ticks, as a killed process would not
    caplog.set_level(logging.WARNING, logger="sim_hw.lockstep")
    start = time.monotonic()
    live.drive.set_velocity(0.2, 0.0)
    await asyncio.wait_for(live.clock.sleep(1.0), timeout=5.0)
    assert time.monotonic() - start < 2.0
    assert server.door.dropped == ["silent"]
    assert "robot silent sent no command for tick 0 within 0.2 s: dropped" in caplog.text
    assert set(server.world.robots) == {"live"}
    await server.door.aclose()


async def test_joins_are_answered_at_the_start_with_the_readings_then() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2)
    first = asyncio.ensure_future(in_process(server, "b"))  # in the world, not answered yet
    await asyncio.sleep(0.05)
    assert not first.done() and list(server.world.robots) == ["b"]
    second = await in_process(server, "a")
    b = await asyncio.wait_for(first, 1)
    assert list(server.world.robots) == ["a", "b"]  # re-created in id order
    # b's first readings are those after the start (a re-created beside it), not at its join
    sonar = server.world.readings("b")["sonar"]
    assert sonar is not None and _ranges(b) == tuple(sonar)
    await asyncio.gather(b.clock.tick(), second.clock.tick())
    assert server.world.tick == 1
    await server.door.aclose()


async def test_the_first_readings_do_not_depend_on_the_order_of_the_joins() -> None:
    async def first_readings(order: str) -> dict[str, Any]:
        server = WorldServer(World(random_obstacles((6.0, 6.0), 4), seed=3), expect=2)
        joins = {n: asyncio.ensure_future(in_process(server, n)) for n in order}  # in order
        hws = {n: await asyncio.wait_for(j, 1) for n, j in joins.items()}
        seen = {n: (_ranges(hw), hw.odometry.pose()) for n, hw in sorted(hws.items())}
        await server.door.aclose()
        return seen

    assert await first_readings("ab") == await first_readings("ba")


async def test_a_dropped_robot_is_told() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=1)
    hw = await in_process(server, "r")
    await server.door.leave("r")
    with pytest.raises(RobotDropped):
        await hw.clock.tick()


async def test_concurrent_waiters_share_one_tick() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2)
    a, b = await asyncio.gather(in_process(server, "a"), in_process(server, "b"))
    await asyncio.gather(a.clock.tick(), a.clock.tick(), a.clock.tick(), b.clock.tick())
    assert server.world.tick == 1
    await server.door.aclose()


async def test_real_time_runs_at_the_speed_factor() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), lockstep=False, speed=20.0)
    hw = await in_process(server, "r")
    start = time.monotonic()
    await hw.clock.sleep(2.0)  # 2 s simulated at 20× ≈ 0.1 s
    elapsed = time.monotonic() - start
    assert 0.08 <= elapsed < 1.0
    assert hw.clock.now() == pytest.approx(2.0, abs=0.15)
    await server.door.aclose()


async def test_late_joiner_enters_at_a_tick_boundary() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=1)
    a = await in_process(server, "a")
    await a.clock.tick()
    joining = asyncio.ensure_future(in_process(server, "b"))
    await asyncio.sleep(0)  # b asks to join ...
    await a.clock.tick()  # ... and is admitted after this tick
    b = await joining
    assert b.clock.now() == a.clock.now() == pytest.approx(0.2)
    await asyncio.gather(a.clock.tick(), b.clock.tick())
    assert server.world.tick == 3
    await server.door.aclose()


async def test_a_robot_waiting_on_its_team_keeps_ticking() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2, timeout=0.2)
    busy, waiting = await asyncio.gather(in_process(server, "busy"), in_process(server, "wait"))
    message: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    async def waiter() -> str:
        async with waiting.clock.ticking():  # e.g. awaiting a distributed_and step
            return await message

    async def worker() -> None:
        await busy.clock.sleep(3.0)  # 30 ticks, each needing the waiter's command too
        message.set_result("done")
        await server.door.leave("busy")  # (else the waiter's last pumped tick would wait for it)

    got, _ = await asyncio.gather(waiter(), worker())
    assert got == "done"
    assert server.door.dropped == []
    assert busy.clock.now() == pytest.approx(3.0)
    assert waiting.clock.now() >= 3.0
    await server.door.aclose()


async def test_a_cancelled_step_does_not_fail_its_retry() -> None:
    """A robot process gives up a step (its task was cancelled) and asks again for the same
    tick: the world cancels the first call, and the retry still gets its readings."""
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2)
    await asyncio.gather(in_process(server, "a"), in_process(server, "b"))
    given_up = asyncio.ensure_future(server.door.step("a", 0, {"v": 0.1, "w": 0.0}))
    await asyncio.sleep(0)
    retry = asyncio.ensure_future(server.door.step("a", 0, {"v": 0.1, "w": 0.0}))
    await asyncio.sleep(0)
    given_up.cancel()  # as the world's RPC server does on the caller's cancel message
    await asyncio.sleep(0)
    late = asyncio.ensure_future(server.door.step("a", 0, {"v": 0.1, "w": 0.0}))  # after the cancel
    await server.door.step("b", 0, {"v": 0.0, "w": 0.0})
    readings = await asyncio.wait_for(asyncio.gather(retry, late), 2.0)
    assert [r["tick"] for r in readings] == [1, 1]
    assert given_up.cancelled()
    await server.door.aclose()
