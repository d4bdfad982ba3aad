"""Cooperative stigmergic navigation (Ducatelle, Di Caro and Gambardella, SAB 2010) as robot
processes: every eye-bot and every foot-bot is a member of the team, of its own kind.

Eye-bots hang from the ceiling and learn, from the foot-bots they see below, which way the
source and the target lie; foot-bots follow their instructions between the two. Both kinds run
this program: the team agrees on a start tick, then one ``distributed_and`` in which each
eye-bot runs its loop (:func:`robots.stigmergic.eyebot_loop`) and each foot-bot its own
(:func:`robots.stigmergic.footbot_loop`) for ``duration`` simulated seconds; with everyone's
results, every member reports the run's figures as the paper measures them (section 5): ``t_1``
the time until the first foot-bot reaches the target, ``t_a`` the mean duration of the trips
after each foot-bot's first.

Every random choice comes from ``team.rng`` (the run's seed): run it again with the same seed
on a lock-step world and it repeats. Launched with the ``survivors`` policy (the shipped team
file is), a member whose process dies mid-run is left out: the others finish, and the figures
are those of the foot-bots that remain (``lost`` names the members that did not).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from mover import RunTeam
from robots import Robot
from robots.stigmergic import (
    EyeBot,
    EyeBotHardware,
    FootBot,
    FootBotHardware,
    Goal,
    Learning,
    Motion,
    Reading,
    eyebot_loop,
    footbot_loop,
    travel_times,
)

from ._start import common_start


async def stigmergic_navigation(
    robot: Robot[Any],
    team: RunTeam,
    duration: float = 300.0,
    period: float = 0.1,
    c_a: float = 0.5,
    c_m: float = 0.99,
    q: float = 0.5,
    d: float = 2.0,
    speed: float = 0.3,
    theta_f: str = "approaching",
) -> dict[str, Any]:
    """Navigate (foot-bots) and learn (eye-bots) for ``duration`` simulated seconds.

    ``period`` is the eye-bots' time step (0.1 s: the simulator's control step; the old reading
    was 1 s), ``theta_f`` which foot-bots they learn θ_f from (``approaching``: those coming
    towards them; ``any``: the old reading, leaving ones too), ``c_a``, ``c_m``, ``q`` their
    learning (eq. 1; the paper's section 5), ``d`` and ``speed`` the foot-bots' leg length and
    speed. Returns the team's figures (``t_1``, ``t_a``, ``t_a_all``, ``trips``, seconds after
    the start; ``lost`` the members gone before the end) and this
    member's own result (``me``: an eye-bot's policies, a foot-bot's trips as
    ``[goal, start, end]`` in simulated seconds).
    """
    hw = robot.hw
    if not isinstance(hw, EyeBotHardware | FootBotHardware):
        raise TypeError(f"{robot.id} is neither an eye-bot nor a foot-bot ({type(hw).__name__})")
    rng = np.random.default_rng(team.rng("stigmergic").getrandbits(128))
    start = await common_start(hw.clock, team)
    until = start + duration
    wall = time.perf_counter()

    async def navigate() -> dict[str, Any]:
        if isinstance(hw, EyeBotHardware):
            eyebot = EyeBot(rng, Learning(c_a=c_a, c_m=c_m, q=q), reading=Reading(theta_f))
            done = await eyebot_loop(hw, eyebot, period, until)
            for policy in ("to_source", "to_target"):  # shorter lines in a report
                done[policy] = [round(p, 4) for p in done[policy]]
            return {"eyebot": done}
        footbot = FootBot(rng, Goal.TARGET, Motion(d=d, speed=speed, dt=hw.clock.tick_period))
        trips = await footbot_loop(hw, footbot, until)
        return {"trips": [t.wire() for t in trips]}

    everyone = await team.distributed_and(navigate)
    wall = time.perf_counter() - wall
    figures = travel_times(
        {m: r["trips"] for m, r in everyone.items() if isinstance(r, dict) and "trips" in r},
        start,
    )
    feet = figures["footbots"]
    lost = sorted(set(team.members) - everyone.keys())  # launched with survivors: gone mid-run
    await team.report(
        "done", t_1=figures["t_1"], t_a=figures["t_a"], trips=figures["trips"], lost=lost
    )
    return {
        **figures,
        "lost": lost,
        "start": start,
        "duration": duration,
        "wall_s": wall,
        "footbot_s_per_wall_s": feet * duration / wall if wall > 0 else None,
        "me": everyone[team.me],
    }
