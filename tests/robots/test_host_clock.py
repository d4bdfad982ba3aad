"""robots.process.HostClock, the host's run clock over a robot's hardware (in one process): on
a lock-step world in-process, and on the HAL fakes of robots.testing."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator

import pytest

from robots.hal import Hardware, HardwareLost
from robots.process import HostClock
from robots.testing import FakeClock, FakeDrive, fake_hardware
from sim_hw import RobotDropped, World, WorldServer, in_process, random_obstacles

Hosted = tuple[WorldServer, HostClock, asyncio.Future[HardwareLost], list[Hardware]]


@contextlib.asynccontextmanager
async def _hosted(*names: str) -> AsyncIterator[Hosted]:
    """A lock-step world in-process with robots ``names``, and a host clock over the first
    one's hardware (with the future it reports a loss on); both closed at the end."""
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=len(names))
    hws = list(await asyncio.gather(*(in_process(server, n) for n in names)))
    lost: asyncio.Future[HardwareLost] = asyncio.get_running_loop().create_future()
    clock = HostClock(hws[0], lost)
    try:
        yield server, clock, lost, hws
    finally:
        await clock.aclose()
        await server.door.aclose()


async def _idle_is(server: WorldServer, idle: list[str]) -> None:
    async with asyncio.timeout(2):
        while sorted(server.door.idle_robots) != idle:
            await asyncio.sleep(0.005)


async def test_release_idles_and_engage_returns_once_the_world_waits_for_us() -> None:
    async with _hosted("a", "b") as (server, clock, _, (a, b)):
        a.drive.set_velocity(0.3, 0.0)
        clock.release()
        clock.release()  # idle already: nothing more
        await _idle_is(server, ["a"])
        await asyncio.wait_for(b.clock.sleep(0.5), 2)
        assert server.world.robots["a"].v == 0.0  # stopped when idling began
        assert clock.now() == pytest.approx(0.5)  # the readings kept coming
        await asyncio.gather(clock.engage(), clock.engage())  # two runs start together
        assert server.door.idle_robots == frozenset()
        passed = asyncio.ensure_future(clock.passed(0.6))
        await asyncio.gather(a.clock.tick(), b.clock.tick())
        assert not passed.done()  # a command on the readings of t = 0.5 is not past 0.6
        await asyncio.gather(a.clock.tick(), b.clock.tick())
        await asyncio.wait_for(passed, 1)  # one on those of t = 0.6 is
        clock.release()
        await _idle_is(server, ["a"])


async def test_a_release_during_an_engage_idles_again() -> None:
    async with _hosted("a") as (server, clock, _, _):
        clock.release()
        await _idle_is(server, ["a"])
        engaging = asyncio.ensure_future(clock.engage())
        await asyncio.sleep(0)
        clock.release()  # the run ended (or was cancelled) before its engage returned
        await engaging
        await _idle_is(server, ["a"])


async def test_a_robot_dropped_while_idle_is_lost() -> None:
    async with _hosted("a") as (server, clock, lost, _):
        clock.release()
        await _idle_is(server, ["a"])
        server.door.drop("a", "left the team")
        assert isinstance(await asyncio.wait_for(lost, 1), RobotDropped)
        with pytest.raises(RobotDropped):
            await clock.engage()


async def test_on_fake_hardware_the_clock_is_the_hardware_s_and_a_loss_is_reported() -> None:
    clock, drive = FakeClock(tick_period=0.1), FakeDrive()
    hw = fake_hardware("a", clock=clock, drive=drive)
    lost: asyncio.Future[HardwareLost] = asyncio.get_running_loop().create_future()
    host = HostClock(hw, lost)
    hw.drive.set_velocity(0.3, 0.0)
    host.release()
    async with asyncio.timeout(1):
        while not clock.idle:
            await asyncio.sleep(0)
    assert (drive.v, drive.omega) == (0.0, 0.0)  # stopped as idling began
    await host.engage()
    assert not clock.idle
    passed = asyncio.ensure_future(host.passed(0.1))
    await clock.tick()
    await clock.tick()  # a command on the readings of t = 0.1
    await asyncio.wait_for(passed, 1)
    assert host.now() == pytest.approx(0.2)
    host.hold(0.2)
    assert clock.held == 0.2
    host.hold(None)
    clock.lose()
    assert isinstance(await asyncio.wait_for(lost, 1), HardwareLost)
    with pytest.raises(HardwareLost):
        await host.engage()
    await host.aclose()
