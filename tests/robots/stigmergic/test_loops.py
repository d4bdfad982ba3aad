"""The eye-bot's and the foot-bot's loops on fake hardware (no world, no network): what they
read from their devices, what they hand to them, when they stop; and the two readings shared
with the in-process runner (the LEDs seen from above, the proximity ring's obstacle)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest

from robots.backend import BaseHardware
from robots.stigmergic import (
    EyeBot,
    EyeBotHardware,
    FootBot,
    FootBotHardware,
    Goal,
    Heard,
    Instruction,
    Spot,
    Trip,
    direction_index,
    eyebot_loop,
    eyebot_procedures,
    footbot_loop,
    footbot_procedures,
    footbot_seen,
    obstacle_bearing,
    perceive,
    read_leds,
    show_leds,
)
from robots.testing import FakeClock

TICK = 0.1


@dataclass
class FakeEye:
    """An eye-bot's camera and transmitter: ``spots`` are in view; ``sent`` is what it sent."""

    spots: tuple[Spot, ...] = ()
    sent: list[tuple[float, Instruction]] = field(default_factory=list)
    clock: FakeClock = field(default_factory=FakeClock)
    view: float = 1.0
    cone: float = 0.5

    def below(self) -> tuple[Spot, ...]:
        return self.spots

    def send(self, instruction: Instruction) -> None:
        self.sent.append((self.clock.now(), instruction))

    def stop(self) -> None:
        pass

    def hardware(self) -> EyeBotHardware:
        return EyeBotHardware("e1", self.clock, camera=self, irrb=self, drive=self)


@dataclass
class FakeFoot:
    """A foot-bot on a straight line: it moves along x at the commanded speed; the target area
    begins at ``target_x``; the eye-bot above and the eye-bots in view are fixed."""

    target_x: float = 1.0
    heard: Heard | None = None
    seen: tuple[tuple[float, float], ...] = ()
    near: float | None = None  # an obstacle straight ahead at this range (m), else clear
    clock: FakeClock = field(default_factory=FakeClock)
    x: float = 0.0
    v: float = 0.0
    leds: list[str] = field(default_factory=list)
    stopped: bool = False
    max_speed: float = 0.3
    max_range: float = 0.3
    angles: tuple[float, ...] = tuple(2.0 * math.pi * k / 8 for k in range(8))

    def __post_init__(self) -> None:
        self.clock.on_tick.append(self._move)

    def _move(self) -> None:
        self.x += self.v * TICK

    # drive, odometry, sonar, LEDs, upward and omni cameras, area sensor
    def set_velocity(self, v: float, omega: float) -> None:
        self.v, self.stopped = v, False

    def stop(self) -> None:
        self.v, self.stopped = 0.0, True

    def pose(self) -> tuple[float, float, float]:
        return (self.x, 0.0, 0.0)

    def ranges(self) -> tuple[float, ...]:
        r = self.max_range
        return (self.near if self.near is not None else r, *([r] * 7))

    def show(self, status: str) -> None:
        self.leds.append(status)

    def above(self) -> Heard | None:
        return self.heard

    def eyebots(self) -> tuple[tuple[float, float], ...]:
        return self.seen

    def area(self) -> Goal | None:
        if self.x >= self.target_x:
            return Goal.TARGET
        return Goal.SOURCE if self.x < -1.0 else None

    def hardware(self) -> FootBotHardware:
        return FootBotHardware(
            "f1",
            self.clock,
            drive=self,
            odometry=self,
            sonar=self,
            led=self,
            up=self,
            omni=self,
            area=self,
        )


def test_both_bundles_are_what_a_robot_process_drives() -> None:
    for hw in (FakeEye().hardware(), FakeFoot().hardware()):
        base: BaseHardware = hw  # the robot process idles the clock, stops the drive
        assert base.radio is None


async def test_an_eye_bot_learns_from_what_its_camera_sees_and_instructs_every_period() -> None:
    # a foot-bot 0.5 m behind (against θ0) going to the target, its front LED towards the
    # eye-bot: it comes from behind (π), where the source is
    going = Spot((-0.5, 0.0), (-0.42, 0.0), show_leds(False, Goal.TARGET))
    fake = FakeEye(spots=(going,))
    eyebot = EyeBot(np.random.default_rng(1))
    done = await eyebot_loop(fake.hardware(), eyebot, period=1.0, until=5.0)
    behind = direction_index(math.pi)
    assert [round(t, 6) for t, _ in fake.sent] == [0.0, 1.0, 2.0, 3.0, 4.0]  # every period
    assert fake.clock.now() == pytest.approx(5.0)  # stopped at `until`
    assert done["seen"] == 5
    assert done["to_source"][behind] == pytest.approx(1.0 / 12 + 5 * 0.5)  # eq. 1, 5 times
    assert done["to_target"][behind] == pytest.approx(1.0 / 12 * 0.99**5)
    # with P_s this peaked, the greedy half of the draws sends foot-bots to the source behind
    sent = [i.to_source for _, i in fake.sent[1:]]
    assert any(direction_index(a) == behind for a in sent)


async def test_an_eye_bot_ignores_what_is_not_a_foot_bots_leds() -> None:
    fake = FakeEye(spots=(Spot((0.3, 0.3), (0.4, 0.3), "blinking"),))
    done = await eyebot_loop(fake.hardware(), EyeBot(np.random.default_rng(2)), 1.0, 2.0)
    assert done["seen"] == 2
    assert done["to_source"] == done["to_target"] == [1.0 / 12] * 12


async def test_a_foot_bot_follows_the_eye_bot_above_and_records_its_trip() -> None:
    # the eye-bot above says: to the target, along θ0, which the upward camera sees ahead
    fake = FakeFoot(target_x=1.0, heard=Heard("e1", 0.0, math.pi, 0.0))
    footbot = FootBot(np.random.default_rng(3), Goal.TARGET)
    trips = await footbot_loop(fake.hardware(), footbot, until=10.0)
    assert len(trips) == 1
    trip = trips[0]
    assert trip.goal is Goal.TARGET and trip.start == 0.0
    # 1 m at 0.3 m/s, the first tick's command applied from the next tick on
    assert trip.end == pytest.approx(3.5, abs=0.25)
    assert trip.wire() == ["target", trip.start, trip.end]
    assert footbot.goal is Goal.SOURCE and footbot.trips == 1
    assert fake.clock.now() == pytest.approx(10.0)
    assert fake.stopped  # the drive is stopped on the way out
    assert read_leds(fake.leds[0]) == (False, Goal.TARGET)  # a forward instruction: LED on


async def test_a_foot_bot_turns_away_from_an_obstacle_ahead_and_shows_it() -> None:
    fake = FakeFoot(target_x=5.0, near=0.05)
    await footbot_loop(fake.hardware(), FootBot(np.random.default_rng(4)), until=0.5)
    assert all(read_leds(s) == (True, None) for s in fake.leds)  # avoiding, front LED off
    assert fake.x == 0.0


async def test_a_foot_bot_loop_that_is_cancelled_stops_its_drive() -> None:
    fake = FakeFoot(target_x=5.0, heard=Heard("e1", 0.0, 0.0, 0.0))

    def stop_here() -> None:
        if fake.clock.ticks == 5:
            raise KeyboardInterrupt  # anything that ends the loop from outside

    fake.clock.on_tick.append(stop_here)
    with pytest.raises(KeyboardInterrupt):
        await footbot_loop(fake.hardware(), FootBot(np.random.default_rng(5)), until=10.0)
    assert fake.stopped


def test_perceive_reads_every_device() -> None:
    heard = Heard("e3", 0.5, 1.0, -1.0)
    fake = FakeFoot(target_x=0.0, heard=heard, seen=((1.5, 0.2),), near=0.05)
    seen = perceive(fake.hardware())
    assert seen.heard == heard and list(seen.eyebots) == [(1.5, 0.2)]
    assert seen.obstacle == 0.0 and seen.at_target and not seen.at_source
    sense = footbot_procedures(fake.hardware())["robot.sense"]()
    assert sense["above"] == ["e3", 0.5, 1.0, -1.0] and sense["area"] == "target"


def test_the_proximity_ring_gives_the_nearest_obstacle_ahead_only() -> None:
    angles = [2.0 * math.pi * k / 8 for k in range(8)]
    clear = [0.3] * 8
    assert obstacle_bearing(clear, angles, 0.1) is None
    ahead_left = clear.copy()
    ahead_left[1] = 0.05  # 45° to the left
    assert obstacle_bearing(ahead_left, angles, 0.1) == pytest.approx(math.pi / 4)
    behind = clear.copy()
    behind[4] = 0.01  # straight behind: not avoided
    assert obstacle_bearing(behind, angles, 0.1) is None
    both = ahead_left.copy()
    both[7] = 0.02  # 45° to the right, nearer
    assert obstacle_bearing(both, angles, 0.1) == pytest.approx(-math.pi / 4)
    assert obstacle_bearing(both, angles, 0.01) is None  # nothing that close


def test_leds_seen_from_above_say_where_a_foot_bot_goes_and_whether_it_avoids() -> None:
    going = footbot_seen((0.0, 0.0), (0.0, 0.1), show_leds(False, Goal.SOURCE), 2.0)
    assert going.goal is Goal.SOURCE and not going.avoiding and going.weight == 2.0
    came_from = going.came_from()
    assert came_from is not None  # heads north: comes from the south
    assert direction_index(came_from) == direction_index(-math.pi / 2)
    avoiding = footbot_seen((0.2, 0.0), None, show_leds(True, None))
    assert avoiding.avoiding and avoiding.goal is None and avoiding.came_from() is None
    other = footbot_seen((0.2, 0.0), (0.3, 0.0), "red")
    assert not other.avoiding and other.goal is None


def test_a_trip_is_plain_data() -> None:
    assert Trip(Goal.SOURCE, 1.5, 9.0).wire() == ["source", 1.5, 9.0]


def test_an_eye_bot_exports_what_its_camera_sees() -> None:
    fake = FakeEye(spots=(Spot((0.5, 0.0), None, show_leds(True, None)),))
    procedures = eyebot_procedures(fake.hardware())
    assert procedures["robot.sense"]() == {
        "time": 0.0,
        "below": [[[0.5, 0.0], None, "avoid/off"]],
    }
    assert procedures["robot.pose"]() == [0.0, 0.0, 0.0]
    procedures["robot.stop"]()  # nothing to stop: it hangs still
