"""The two behaviours on their hardware: an eye-bot's loop and a foot-bot's loop.

Each drives its pure step function (:class:`EyeBot`, :class:`FootBot`) through the HAL of its
kind (:mod:`robots.stigmergic._hal`) until a given time of the hardware's clock, and returns
what it did: an eye-bot its policies and how many foot-bots it saw, a foot-bot its trips
(:class:`Trip`, with their simulated start and end times).

* eye-bot, every ``period`` seconds (section 4.2): learn from the foot-bots in the downward
  camera's view, draw θ_s and θ_t, hand them to the IrRB transmitter;
* foot-bot, every tick (sections 4.3–4.4): odometry, the proximity ring (the nearest obstacle
  ahead closer than ``avoid`` to its rim), the instruction heard from the eye-bot above, the
  eye-bots the omnidirectional camera sees and the area sensor make its perception; its wheel
  speeds go to the drive and its two lights to the LEDs. A trip ends when the goal is reached
  (the behaviour turns its goal over); the first one starts when the loop does.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._eyebot import EyeBot, Goal
from ._footbot import FootBot, FootPerception
from ._hal import EyeBotHardware, FootBotHardware, footbot_seen, obstacle_bearing
from ._leds import show as show_leds

AVOID = 0.1
"""A foot-bot avoids what is within this distance of its rim (m)."""


@dataclass(frozen=True, slots=True)
class Trip:
    """One trip of a foot-bot: to ``goal``, from ``start`` to ``end`` (hardware seconds)."""

    goal: Goal
    start: float
    end: float

    def wire(self) -> list[Any]:
        """As plain data: ``[goal, start, end]``."""
        return [self.goal.value, self.start, self.end]


async def eyebot_loop(
    hw: EyeBotHardware, eyebot: EyeBot, period: float, until: float
) -> dict[str, Any]:
    """Observe, learn and instruct every ``period`` s until the clock reaches ``until``.

    Returns ``seen`` (foot-bot observations made) and the policies' preferences
    (``to_source``, ``to_target``: 12 numbers each, direction 0 along θ0).
    """
    seen = 0
    clock = hw.clock
    while clock.now() < until - 1e-9:
        spots = hw.camera.below()
        seen += len(spots)
        hw.irrb.send(eyebot.step([footbot_seen(s.beacon, s.front, s.led) for s in spots]))
        await clock.sleep(min(period, max(until - clock.now(), clock.tick_period)))
    return {
        "seen": seen,
        "to_source": list(eyebot.to_source.preferences),
        "to_target": list(eyebot.to_target.preferences),
    }


def perceive(hw: FootBotHardware, avoid: float = AVOID) -> FootPerception:
    """What the foot-bot's behaviour takes in this tick, from its devices."""
    area = hw.area.area()
    return FootPerception(
        pose=hw.odometry.pose(),
        heard=hw.up.above(),
        eyebots=hw.omni.eyebots(),
        obstacle=obstacle_bearing(hw.sonar.ranges(), hw.sonar.angles, avoid),
        at_source=area is Goal.SOURCE,
        at_target=area is Goal.TARGET,
    )


async def footbot_loop(
    hw: FootBotHardware, footbot: FootBot, until: float, avoid: float = AVOID
) -> list[Trip]:
    """Step the foot-bot every tick until the clock reaches ``until``; its trips.

    The drive is stopped on the way out, whatever ends the loop.
    """
    clock = hw.clock
    trips: list[Trip] = []
    started = clock.now()
    try:
        while clock.now() < until - 1e-9:
            goal = footbot.goal
            command = footbot.step(perceive(hw, avoid))
            if footbot.goal is not goal:
                now = clock.now()
                trips.append(Trip(goal, started, now))
                started = now
            hw.drive.set_velocity(command.v, command.w)
            hw.led.show(show_leds(command.avoiding, command.front))
            await clock.tick()
    finally:
        hw.drive.stop()
    return trips


def travel_times(
    trips: Mapping[str, list[list[Any]]], start: float, duration: float | None = None
) -> dict[str, Any]:
    """The paper's figures from every foot-bot's trips (``[goal, start, end]`` each): ``t_1``
    (the first arrival at the target, seconds after ``start``), ``t_a`` (the mean trip after
    each foot-bot's first; the first one starts in exploration), ``t_a_median`` (their median:
    a few lost trips pull the mean up), ``t_a_all`` (every trip), ``trips``, ``later`` (how
    many trips ``t_a`` averages) and ``footbots``; given the run's ``duration``, ``t_a_late``
    and ``late``: the same as ``t_a`` over the later trips begun in the run's second half
    (learning mostly done). None where there is no trip to count."""
    arrivals = [end for bot in trips.values() for goal, _, end in bot if goal == Goal.TARGET.value]
    later = [(begin, end - begin) for bot in trips.values() for _, begin, end in bot[1:]]
    every = [end - begin for bot in trips.values() for _, begin, end in bot]
    times = [t for _, t in later]
    out = {
        "t_1": min(arrivals) - start if arrivals else None,
        "t_a": float(np.mean(times)) if times else None,
        "t_a_median": float(np.median(times)) if times else None,
        "t_a_all": float(np.mean(every)) if every else None,
        "trips": len(every),
        "later": len(times),
        "footbots": len(trips),
    }
    if duration is not None:
        late = [t for begin, t in later if begin >= start + duration / 2]
        out["t_a_late"] = float(np.mean(late)) if late else None
        out["late"] = len(late)
    return out
