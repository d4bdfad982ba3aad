"""robots.testing, the HAL fakes shipped for users: they satisfy the HAL protocols (the
continuous and the grid one) and behave as the simulated hardware does (ticks, hold, passed,
idling, a lost hardware; a grid round's end)."""

from __future__ import annotations

import asyncio
import math

import pytest

from mover import IdleClock
from robots.grid_hal import (
    GridDrive,
    GridFloor,
    GridGripper,
    GridHardware,
    GridOdometry,
    GridRadio,
    GridSenses,
    RoundClock,
)
from robots.hal import Clock, Drive, Hardware, HardwareLost, Odometry, Sonar
from robots.testing import (
    FakeClock,
    FakeDrive,
    FakeGridDrive,
    FakeGridFloor,
    FakeGridGripper,
    FakeGridRadio,
    FakeOdometry,
    FakeRoundClock,
    FakeSonar,
    fake_grid_hardware,
    fake_hardware,
)

NORTH, EAST, SOUTH, WEST = range(4)


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


# -- the grid HAL's fakes ------------------------------------------------------------------------


def test_the_grid_fakes_are_the_grid_hal_s_devices() -> None:
    hw = fake_grid_hardware("ant", radio=FakeGridRadio(range=3.0))
    assert isinstance(hw, GridHardware) and hw.id == "ant"
    assert isinstance(hw.clock, RoundClock) and isinstance(hw.clock, IdleClock)
    assert isinstance(hw.drive, GridDrive) and isinstance(hw.odometry, GridOdometry)
    assert isinstance(hw.senses, GridSenses) and isinstance(hw.floor, GridFloor)
    assert isinstance(hw.gripper, GridGripper) and isinstance(hw.radio, GridRadio)
    assert fake_grid_hardware().radio is None


async def test_a_round_ends_with_what_the_robot_asked_for() -> None:
    drive, floor = FakeGridDrive(blocked={NORTH}), FakeGridFloor(value=4)
    gripper = FakeGridGripper(lying=3)
    hw = fake_grid_hardware(drive=drive, floor=floor, gripper=gripper)
    hw.drive.move(EAST)
    hw.floor.write(7)
    hw.floor.scent(0.5)
    hw.gripper.pick(5)
    assert hw.floor.read() == (7, 0) and floor.value == 4  # a pending write shows at once
    await hw.clock.tick()
    assert hw.clock.now() == 1 and hw.drive.moved() and hw.odometry.pose() == (0.0, 1.0, 0.0)
    assert (floor.value, floor.pheromone) == (7, 0.5) and hw.gripper.carried() == 3
    hw.drive.move(NORTH)  # blocked: the robot stays
    hw.gripper.drop()
    await hw.clock.tick()
    assert not hw.drive.moved() and hw.odometry.pose() == (0.0, 1.0, 0.0)
    assert (gripper.load, gripper.dropped, gripper.lying) == (0, 3, 0)
    await hw.clock.tick()  # nothing asked: nothing moves
    assert not hw.drive.moved() and drive.commands == [EAST, NORTH]


async def test_a_round_clock_is_owned_from_its_round_until_the_observer_ends_the_run() -> None:
    clock = FakeRoundClock(end=4)
    hw = fake_grid_hardware(clock=clock)
    hw.drive.move(SOUTH)
    async with hw.clock.owned(at=2):  # the clock gets there itself: the first round moves
        assert hw.clock.now() == 2 and hw.odometry.pose() == (1.0, 0.0, 0.0)
        with pytest.raises(RuntimeError, match="already owned"):
            async with hw.clock.owned(at=3):
                pass
        while not hw.clock.ended():
            await hw.clock.tick()
    assert hw.clock.now() == 4
    with pytest.raises(RuntimeError, match="round 3 had already passed"):
        async with hw.clock.owned(at=3):
            pass
    clock.hold(4)  # held in rounds, as the continuous clock in seconds
    await hw.clock.tick()
    later = asyncio.ensure_future(hw.clock.tick())
    await asyncio.sleep(0.01)
    assert not later.done() and hw.clock.now() == 5
    hw.clock.hold(None)
    await asyncio.wait_for(later, 1)
    await asyncio.wait_for(hw.clock.passed(5), 1)


async def test_an_idle_grid_robot_stays() -> None:
    hw = fake_grid_hardware()
    hw.drive.move(WEST)
    async with hw.clock.idling():
        with pytest.raises(RuntimeError):
            await hw.clock.tick()
    await hw.clock.tick()
    assert not hw.drive.moved() and hw.odometry.pose() == (0.0, 0.0, 0.0)
