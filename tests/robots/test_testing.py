"""robots.testing, the HAL fakes shipped for users: they satisfy the HAL protocols and behave
as the simulated hardware does (ticks, hold, passed, idling, a lost hardware)."""

from __future__ import annotations

import asyncio
import math

import pytest

from mover import IdleClock
from robots.hal import Clock, Drive, Hardware, HardwareLost, Odometry, Sonar
from robots.testing import FakeClock, FakeDrive, FakeOdometry, FakeSonar, fake_hardware


def test_the_fakes_are_the_hal_s_devices() -> None:
    hw = fake_hardware("ada")
    assert isinstance(hw, Hardware) and hw.id == "ada"
    assert isinstance(hw.clock, Clock) and isinstance(hw.clock, IdleClock)
    assert isinstance(hw.drive, Drive) and isinstance(hw.odometry, Odometry)
    assert isinstance(hw.sonar, Sonar)


async def test_a_clock_ticks_whole_periods_and_runs_its_hooks() -> None:
    clock = FakeClock(tick_period=0.25, start=1.0)
    seen: list[float] = []
    clock.on_tick.append(lambda: seen.append(clock.now()))
    await clock.tick()
    await clock.sleep(0.6)  # whole ticks: three
    assert clock.ticks == 4 and clock.now() == pytest.approx(2.0)
    assert seen == pytest.approx([1.25, 1.5, 1.75, 2.0])
    await clock.sleep(0.0)  # at least one
    assert clock.ticks == 5
    async with clock.ticking():
        assert clock.ticks == 5


async def test_passed_waits_for_a_command_on_readings_of_that_time() -> None:
    clock = FakeClock(tick_period=0.5)
    passed = asyncio.ensure_future(clock.passed(0.5))
    await clock.tick()  # a command on the readings of t = 0
    assert not passed.done()
    await clock.tick()  # one on those of t = 0.5
    await asyncio.wait_for(passed, 1)
    await asyncio.wait_for(clock.passed(0.0), 1)  # at once: it has


async def test_a_held_clock_hands_in_nothing_past_the_hold_until_released() -> None:
    clock = FakeClock(tick_period=1.0)
    clock.hold(1.0)
    await clock.tick()
    await clock.tick()  # on the readings of t = 1: allowed
    later = asyncio.ensure_future(clock.tick())  # on those of t = 2: held
    await asyncio.sleep(0.01)
    assert not later.done() and clock.now() == 2.0
    clock.hold(None)
    await asyncio.wait_for(later, 1)
    assert clock.now() == 3.0


async def test_idling_stops_the_drive_and_refuses_ticks() -> None:
    drive = FakeDrive()
    hw = fake_hardware(drive=drive)
    hw.drive.set_velocity(0.2, 0.1)
    async with hw.clock.idling():
        assert drive.v == 0.0 and drive.omega == 0.0
        with pytest.raises(RuntimeError):
            await hw.clock.tick()
    await hw.clock.tick()
    assert drive.commands == [(0.2, 0.1), (0.0, 0.0)]


async def test_a_lost_clock_raises_hardware_lost_and_wakes_its_waiters() -> None:
    clock = FakeClock()
    passed = asyncio.ensure_future(clock.passed(math.inf))
    await asyncio.sleep(0)
    clock.lose()
    with pytest.raises(HardwareLost):
        await asyncio.wait_for(passed, 1)
    with pytest.raises(HardwareLost):
        await clock.tick()
    with pytest.raises(HardwareLost):
        async with clock.idling():
            pass


async def test_the_odometry_follows_the_drive_every_tick() -> None:
    odometry = FakeOdometry((1.0, 0.0, math.pi / 2))
    hw = fake_hardware(clock=FakeClock(tick_period=0.5), odometry=odometry)
    hw.drive.set_velocity(0.2, 0.0)
    await hw.clock.sleep(1.0)
    x, y, h = hw.odometry.pose()
    assert (x, y, h) == pytest.approx((1.0, 0.2, math.pi / 2))
    hw.drive.set_velocity(0.0, math.pi)  # half a turn in one second: heading wraps
    await hw.clock.sleep(1.0)
    assert hw.odometry.pose()[2] == pytest.approx(-math.pi / 2)


def test_a_sonar_reads_what_the_test_sets() -> None:
    sonar = FakeSonar(angles=(0.0, 1.0), max_range=1.5)
    assert sonar.ranges() == (1.5, 1.5)
    sonar.readings = (0.2, 1.5)
    assert fake_hardware(sonar=sonar).sonar is sonar
    assert sonar.ranges() == (0.2, 1.5)
