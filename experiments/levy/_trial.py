"""One seeded Lévy-search trial in-process, on the pymunk world, and the seeds of a sweep.

A trial builds a 20 × 20 m arena (seeded random obstacles, :func:`sim_hw.continuous.
random_obstacles`), places the targets (passive beacons a robot can mark, ``MarkerSpec.hears``)
and the robots at random free points, and steps the world tick by tick: every robot's
:class:`robots.library.LevyWalker` gets its sonar, bumper and camera readings and the robots
it hears (below), and its command goes back to the world; marks travel as the robot's LED
message, which the target hears within the sensing range. The trial ends when every target is
marked (its search time: when the last one was) or at ``Setup.max_time`` (censored).

The neighbours a robot hears are what mover's range-limited broadcast gives a robot that
broadcasts its presence every tick (``mover/_radio.py``): every robot within ρ0 of it, by the
radio locators' positions of this tick, with distance and bearing in the receiver's frame.

The arena, targets and robots' starts of run k depend on the master seed, k and the counts
only, so the three methods are compared on the same arenas (paired trials).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from robots.hal import Sighting
from robots.library import MARK, WALKS, Neighbour, levy_sense, walker
from sim_hw.continuous import (
    TICK,
    CameraSpec,
    MarkerSpec,
    RobotSpec,
    SonarSpec,
    World,
    WorldSpec,
    free_points,
    random_obstacles,
)

from ._paper import Setup

METHOD_CODES = {"FL": 0, "L": 1, "L+P": 2, "L+F": 3, "L+S": 4, "FL+S": 5}
"""Each walk's part of its robots' seeds (the arenas do not depend on it)."""


def seeds(master: int, run: int, robots: int, targets: int) -> dict[str, np.random.SeedSequence]:
    """The seed sequences of run ``run``: the arena (obstacles), the targets and the robots'
    starts (the walkers': ``[master, run, 3, robots, targets, method, robot]``)."""
    return {
        "arena": np.random.SeedSequence([master, run]),
        "targets": np.random.SeedSequence([master, run, 1, targets]),
        "starts": np.random.SeedSequence([master, run, 2, robots, targets]),
    }


def arena(setup: Setup, robots: int, targets: int, master: int, run: int) -> WorldSpec:
    """The world of run ``run``: obstacles, targets, and the robots ``r00``, ``r01``, … at
    their random start poses."""
    ss = seeds(master, run, robots, targets)
    size = (setup.size, setup.size)
    spec = random_obstacles(
        size,
        setup.obstacles,
        np.random.default_rng(ss["arena"]),
        min_size=setup.obstacle_min,
        max_size=setup.obstacle_max,
        clearance=1.0,
    )
    spots = free_points(spec, targets, np.random.default_rng(ss["targets"]), apart=2.0)
    hears = setup.walk.sense_range + 0.15  # the robot brakes from 0.6 m/s in the tick it marks
    markers = tuple(MarkerSpec("target", f"t{i}", p, 0.2, "", hears) for i, p in enumerate(spots))
    spec = replace(spec, name=f"levy-{run}", markers=markers, robot=robot_spec(setup))
    rng = np.random.default_rng(ss["starts"])
    starts = free_points(spec, robots, rng, apart=0.6)
    poses = {
        f"r{i:02d}": replace(spec.robot, pose=(x, y, float(rng.uniform(-math.pi, math.pi))))
        for i, (x, y) in enumerate(starts)
    }
    return replace(spec, robots=poses)


def robot_spec(setup: Setup) -> RobotSpec:
    """The experiment's robot: 0.15 m discs at up to ``speed``, an 8-ray sonar, and an
    all-round camera out to the signature range (targets transmit to every side)."""
    return RobotSpec(
        radius=0.15,
        max_speed=setup.walk.speed,
        max_turn=2.0,
        sonar=SonarSpec(rays=8, max_range=1.0),
        camera=CameraSpec(max_range=setup.walk.signature_range, fov=2 * math.pi),
    )


def heard(locs: list[tuple[float, float, float]], i: int, reach: float) -> tuple[Neighbour, ...]:
    """(distance, bearing) of every robot within ``reach`` of robot ``i``, as the radio gives."""
    x, y, heading = locs[i]
    out = []
    for j, (ox, oy, _) in enumerate(locs):
        if j == i:
            continue
        d = math.hypot(ox - x, oy - y)
        if d <= reach:
            b = math.atan2(oy - y, ox - x) - heading
            out.append((d, math.atan2(math.sin(b), math.cos(b))))
    return tuple(out)


def run_world(
    spec: WorldSpec, method: str, setup: Setup, key: Sequence[int], world_seed: int = 0
) -> dict[str, Any]:
    """A search on ``spec`` (its robots in ``spec.robots``, with their poses) until every
    target is marked or ``setup.max_time``. Robot i (in id order) walks with the generator
    seeded ``[*key, i]``, as ``programs/levy_search.py`` seeds it. As a robot process does,
    the robots tick once before their first decision; times count from there."""
    t0 = time.perf_counter()
    world = World(spec, seed=world_seed)
    ids = sorted(spec.robots)
    for rid in ids:
        world.add_robot(rid)
    walks = [
        walker(
            method,
            np.random.default_rng([*key, i]),
            alpha=setup.alpha,
            scale=setup.scale,
            cap=setup.cap,
            fixed=setup.fixed,
            params=setup.walk,
        )
        for i in range(len(ids))
    ]
    angles = spec.robot.sonar.angles() if spec.robot.sonar else ()
    targets = sum(m.hears > 0 for m in spec.markers)
    world.step()
    start = world.time
    limit = world.tick + round(setup.max_time / TICK)
    while len(world.marked) < targets and world.tick < limit:
        readings = [world.readings(rid) for rid in ids]
        locs = [(r["loc"][0], r["loc"][1], r["loc"][2]) for r in readings if r["loc"]]
        for i, (rid, r) in enumerate(zip(ids, readings, strict=True)):
            seen = [Sighting(*c) for c in r["cam"] or ()]
            bump = r["bump"] is not None
            near = heard(locs, i, setup.walk.rho0)
            cmd = walks[i].step(levy_sense(TICK, r["sonar"] or (), angles, bump, seen, near))
            led = "" if cmd.mark is None else MARK + cmd.mark
            world.set_command(rid, {"v": cmd.v, "w": cmd.w, "led": led})
        world.step()
    found = sorted(t - start for t in world.marked.values())
    done = len(found) == targets
    return {
        "method": method,
        "robots": len(ids),
        "targets": targets,
        "alpha": setup.alpha,
        "fixed": None if WALKS[method][0] else setup.fixed,
        "time": found[-1] if done and found else None,
        "found": found,
        "sim_s": world.time - start,
        "robot_s": (world.time - start) * len(ids),
        "wall_s": time.perf_counter() - t0,
    }


def run_trial(
    setup: Setup, method: str, robots: int, targets: int, master: int, run: int
) -> dict[str, Any]:
    """Run ``run`` of a point: its arena (:func:`arena`) searched by ``method``; returns its
    search time (None if censored), when each target was found, and the simulated
    robot-seconds and wall seconds it took."""
    spec = arena(setup, robots, targets, master, run)
    key = [master, run, 3, robots, targets, METHOD_CODES[method]]
    return {**run_world(spec, method, setup, key, master), "run": run}


def world_data(spec: WorldSpec) -> dict[str, Any]:
    """``spec`` as the content of a JSON world file (``sim_hw.continuous.load_world``): for a
    world process to run the same arena as :func:`run_world` does in-process (load the file
    on both sides: its angles are degrees)."""
    r = spec.robot
    robot: dict[str, Any] = {"radius": r.radius, "max_speed": r.max_speed, "max_turn": r.max_turn}
    if r.sonar is not None:
        robot["sonar"] = {"rays": r.sonar.rays, "max_range": r.sonar.max_range}
    if r.camera is not None:
        robot["camera"] = {
            "max_range": r.camera.max_range,
            "fov": math.degrees(r.camera.fov),
            "occlusion": r.camera.occlusion,
        }
    obstacles = []
    for ob in spec.obstacles:
        if ob.shape == "circle":
            obstacles.append({"shape": "circle", "center": list(ob.center), "radius": ob.radius})
        else:
            obstacles.append(
                {
                    "shape": "box",
                    "center": list(ob.center),
                    "size": list(ob.size),
                    "angle": math.degrees(ob.angle),
                }
            )
    return {
        "world": {"name": spec.name, "size": list(spec.size)},
        "robot": robot,
        "robots": [
            {"id": rid, "pose": [p[0], p[1], math.degrees(p[2])]}
            for rid, rs in sorted(spec.robots.items())
            if (p := rs.pose) is not None
        ],
        "obstacles": obstacles,
        "targets": [
            {"id": m.id, "center": list(m.center), "radius": m.radius, "hears": m.hears}
            for m in spec.markers
        ],
    }
