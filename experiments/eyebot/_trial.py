"""One seeded run of stigmergic navigation in-process: eye-bots, foot-bots, the pymunk world.

Each tick (0.1 s of simulated time, the simulator's control step) the ceiling layer
(:class:`sim_hw.continuous.Ceiling`) gives the devices between the two kinds of robot; each
foot-bot's :class:`robots.stigmergic.FootBot` gets its odometry, its proximity ring (an 8-ray
range sensor out to ``PROXIMITY`` m; the nearest obstacle within ±90° of its heading and
closer than ``AVOID`` m to its rim is avoided), the instruction of the eye-bot above it, the
eye-bots its omnidirectional camera sees, and whether it is in the source or the target area;
its wheel speeds and LEDs go back to the world. Every
``Settings.period`` seconds (by default every tick: the paper's eye-bots act at the simulator's
discrete step; the old reading was 1 s) each eye-bot learns from the foot-bots in its view and
draws a new instruction.

Measured, as the paper does (section 5): ``t_1`` the time until the first foot-bot reaches the
target; ``t_a`` the mean duration of the trips between source and target after each foot-bot's
first one (the first is exploration from the start; counting it too is ``t_a_all``;
``t_a_late`` counts only those begun in the run's second half); for the
double corridor, over the last ``window`` seconds, how many foot-bots are in the right corridor
and in the left one at each tick, and ρ = c_r / (c_r + c_l) (in the mirrored arena c_r counts
the shorter corridor, on the left there, so that ρ is always the shorter corridor's share).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from robots.stigmergic import (
    EyeBot,
    FootBot,
    FootBotSeen,
    FootPerception,
    Goal,
    Heard,
    Instruction,
    Learning,
    Motion,
    Reading,
    footbot_seen,
    obstacle_bearing,
    show_leds,
    travel_times,
    trip_weight,
)
from sim_hw.continuous import TICK, Ceiling, RobotSpec, SonarSpec, World

from ._arena import AREA, Arena

PROXIMITY = 0.3
"""Range of the foot-bot's proximity ring (m)."""
AVOID = 0.1
"""A foot-bot avoids what is within this distance of its rim (m)."""
FOOT = RobotSpec(
    radius=0.085,
    mass=1.8,
    force=20.0,
    track=0.14,
    max_speed=0.3,
    max_turn=2.0,
    sonar=SonarSpec(rays=8, max_range=PROXIMITY),
    camera=None,
    radio=False,
)


@dataclass(frozen=True)
class Settings:
    """One run's settings: 3000 s, the paper's constants, foot-bots deployed at once."""

    footbots: int = 1
    duration: float = 3000.0
    deploy_every: float = 0.0
    shortest: bool = False
    weigh: bool = False
    weigh_reference: float = 60.0
    period: float = TICK
    reading: Reading = Reading.APPROACHING
    window: float = 1000.0
    learning: Learning = field(default_factory=Learning)
    motion: Motion = field(default_factory=Motion)


def run(arena: Arena, settings: Settings, seed: int) -> dict[str, Any]:
    """One run; its figures as a plain dict (JSON-ready)."""
    wall = time.perf_counter()
    world = World(arena.spec, seed=seed)
    ceiling = Ceiling(world, arena.eyebots)
    rng = np.random.SeedSequence([seed])
    eye_seq, foot_seq, place_seq = rng.spawn(3)
    eyes = {
        e.id: EyeBot(np.random.default_rng(s), settings.learning, reading=settings.reading)
        for e, s in zip(arena.eyebots, eye_seq.spawn(len(arena.eyebots)), strict=True)
    }
    if settings.shortest:
        for eid, eye in eyes.items():
            eye.show_shortest(*arena.shortest[eid])
    foot_rngs = [np.random.default_rng(s) for s in foot_seq.spawn(settings.footbots)]
    place = np.random.default_rng(place_seq)
    feet: dict[str, FootBot] = {}
    started: dict[str, float] = {}  # when each foot-bot's current trip began
    trips: list[dict[str, Any]] = []
    instructions: dict[str, Instruction] = {}
    period = max(1, round(settings.period / TICK))
    deploy = max(1, round(settings.deploy_every / TICK)) if settings.deploy_every else 0
    ticks = round(settings.duration / TICK)
    window_from = ticks - round(settings.window / TICK)
    counts = [0, 0]  # foot-bot-ticks in the right, the left corridor (last window)
    for tick in range(ticks):
        due = len(feet) < settings.footbots and (deploy == 0 or tick % deploy == 0 or not feet)
        while due and len(feet) < settings.footbots:
            rid = f"f{len(feet):02d}"
            world.add_robot(rid, _start(arena, world, place))
            feet[rid] = FootBot(foot_rngs[len(feet)], Goal.TARGET, settings.motion)
            started[rid] = world.time
            world.set_command(rid, {"led": show_leds(False, None)})
            due = deploy == 0
        ceiling.sense()
        if tick % period == 0:
            # at one tick a step, an instruction nobody is under now is never heard: it is not
            # drawn (the draws that are heard are distributed the same; a third less work)
            heard = _under(ceiling, feet) if period == 1 else None
            for eid, eye in eyes.items():
                seen = [_seen(b, started, world.time, settings) for b in ceiling.camera(eid)]
                if heard is None or eid in heard:
                    instructions[eid] = eye.step(seen)
                else:
                    eye.observe(seen)
                    instructions.pop(eid, None)
        for rid, bot in feet.items():
            goal = bot.goal
            command = bot.step(_perceive(arena, world, ceiling, rid, instructions))
            if bot.goal is not goal:
                now = world.time
                trips.append({"robot": rid, "to": goal.value, "start": started[rid], "end": now})
                started[rid] = now
            world.set_command(
                rid,
                {"v": command.v, "w": command.w, "led": show_leds(command.avoiding, command.front)},
            )
        if arena.corridors is not None and tick >= window_from:
            _count(arena, world, feet, counts)
        world.step()
    return _figures(arena, settings, seed, trips, counts, time.perf_counter() - wall)


def _start(arena: Arena, world: World, rng: np.random.Generator) -> RobotSpec:
    """A free pose in the source area (clear of the foot-bots already there)."""
    sx, sy = arena.source
    taken = [world.pose(r)[:2] for r in world.robots]
    for _ in range(1000):
        r, a = AREA * 0.8 * math.sqrt(float(rng.random())), float(rng.uniform(-math.pi, math.pi))
        x, y = sx + r * math.cos(a), sy + r * math.sin(a)
        w, h = arena.spec.size
        if not (0.2 < x < w - 0.2 and 0.2 < y < h - 0.2):
            continue
        if all(math.dist((x, y), t) > 2.5 * FOOT.radius for t in taken):
            heading = float(rng.uniform(-math.pi, math.pi))
            return replace(FOOT, pose=(x, y, heading))
    raise RuntimeError("no free place in the source area")


def _under(ceiling: Ceiling, feet: dict[str, FootBot]) -> set[str]:
    """The eye-bots some foot-bot is under (in the cone of) now."""
    return {a[0] for r in feet if (a := ceiling.above(r)) is not None}


def _seen(below: Any, started: dict[str, float], now: float, settings: Settings) -> FootBotSeen:
    weight = 1.0
    if settings.weigh:
        weight = trip_weight(now - started.get(below.robot, now), settings.weigh_reference)
    return footbot_seen(below.beacon, below.front, below.led, weight)


def _perceive(
    arena: Arena,
    world: World,
    ceiling: Ceiling,
    rid: str,
    instructions: dict[str, Instruction],
) -> FootPerception:
    readings = world.readings(rid)
    odom = readings["odom"]
    pose = (float(odom[0]), float(odom[1]), float(odom[2]))
    ranges = readings["sonar"] or []
    angles = [2.0 * math.pi * k / len(ranges) for k in range(len(ranges))]
    obstacle = obstacle_bearing(ranges, angles, AVOID)
    heard = None
    above = ceiling.above(rid)
    if above is not None and above[0] in instructions:
        instr = instructions[above[0]]
        heard = Heard(above[0], above[1], instr.to_source, instr.to_target)
    x, y, _ = world.pose(rid)  # the area sensors (a floor colour, say)
    return FootPerception(
        pose=pose,
        heard=heard,
        eyebots=ceiling.omni(rid),
        obstacle=obstacle,
        at_source=arena.in_source(x, y),
        at_target=arena.in_target(x, y),
    )


def _count(arena: Arena, world: World, feet: dict[str, FootBot], counts: list[int]) -> None:
    assert arena.corridors is not None
    divide, y0, y1 = arena.corridors
    for rid in feet:
        x, y, _ = world.pose(rid)
        if y0 < y < y1:  # mirrored: the shorter corridor, counted first, is the left one
            counts[0 if (x > divide) != arena.mirrored else 1] += 1


def _figures(
    arena: Arena,
    settings: Settings,
    seed: int,
    trips: list[dict[str, Any]],
    counts: list[int],
    wall: float,
) -> dict[str, Any]:
    by_robot: dict[str, list[list[Any]]] = {}
    for trip in trips:
        by_robot.setdefault(trip["robot"], []).append([trip["to"], trip["start"], trip["end"]])
    times = travel_times(by_robot, 0.0, settings.duration)
    total = counts[0] + counts[1]
    return {
        "arena": arena.spec.name,
        "run_seed": seed,
        "footbots": settings.footbots,
        "shortest": settings.shortest,
        "weigh": settings.weigh,
        "duration": settings.duration,
        "window": min(settings.window, settings.duration),
        "period": settings.period,
        "reading": settings.reading.value,
        "head_on_right": settings.motion.head_on_right,
        "t_1": times["t_1"],
        "t_a": times["t_a"],
        "t_a_median": times["t_a_median"],
        "t_a_all": times["t_a_all"],
        "t_a_late": times["t_a_late"],
        "trips": times["trips"],
        "later": times["later"],
        "late": times["late"],
        "c_r": counts[0],
        "c_l": counts[1],
        "rho": counts[0] / total if total else None,
        "wall_s": wall,
        "robot_s_per_wall_s": settings.footbots * settings.duration / wall if wall else None,
    }
