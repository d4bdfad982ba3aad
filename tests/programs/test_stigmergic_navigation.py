"""programs/stigmergic_navigation.py as robot processes of two kinds: the shipped team file's
11 eye-bots and 5 foot-bots (16 members: a router) brought up by ``mover up`` on a lock-step
world with a ceiling, the program launched for a short run. Every foot-bot process navigates
and records its trips in simulated time, the eye-bots learn from what they see, and every
member reports the same figures. A foot-bot and an eye-bot killed mid-run (the run launched
with the ``survivors`` policy) are left out: the others finish and agree on the figures.

The run starts the foot-bots a metre from the target area (in a copy of the shipped world) so
that trips happen within the 80 simulated seconds of the test; the long run that shows
learning is ``mover up teams/stigmergic_navigation.toml --exit-after-run``
(results/eyebot/distributed.txt)."""

from __future__ import annotations

import asyncio
import json
import math
import os
import signal
import tomllib
from pathlib import Path
from typing import Any

import pytest

from mover import launch

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]
DURATION = 80.0
NEAR_TARGET = [[2.3, 0.6, 180], [2.3, 1.0, 180], [2.3, 1.4, 180], [2.7, 0.8, 150], [2.7, 1.3, 210]]


def _files(tmp_path: Path) -> tuple[Path, list[str], list[str]]:
    """A copy of the shipped world (foot-bots near the target) and of the team file without its
    program (the test launches it); the eye-bots' and the foot-bots' names."""
    data = tomllib.loads((ROOT / "worlds" / "stigmergic_navigation.toml").read_text())
    for robot, pose in zip(data["robots"], NEAR_TARGET, strict=True):
        robot["pose"] = pose
    world = tmp_path / "world.json"
    world.write_text(json.dumps(data))
    team = (ROOT / "teams" / "stigmergic_navigation.toml").read_text()
    team = team.replace('"../worlds/stigmergic_navigation.toml"', json.dumps(str(world)))
    team = team.split("[program]")[0]
    path = tmp_path / "team.toml"
    path.write_text(team)
    return path, [e["id"] for e in data["eyebots"]], [r["id"] for r in data["robots"]]


async def _team(mover_up: Any, tmp_path: Path) -> tuple[Any, list[str], list[str]]:
    """The team of :func:`_files` brought up; the eye-bots' and the foot-bots' names."""
    path, eyes, feet = _files(tmp_path)
    return await mover_up(str(path)), eyes, feet


@pytest.mark.timeout(150)
async def test_eye_bots_and_foot_bots_as_robot_processes_navigate_and_learn(
    mover_up: Any, tmp_path: Path
) -> None:
    up, eyes, feet = await _team(mover_up, tmp_path)
    assert any("router" in line for line in up.lines)  # 16 members: over a peer mesh's size
    outcomes = await asyncio.wait_for(
        launch(
            up.node, "stigmergic_navigation", eyes + feet, {"duration": DURATION}, run="s", seed=3
        ),
        120,
    )
    results: dict[str, Any] = {m: o.get("result") for m, o in outcomes.items()}
    assert all(r is not None for r in results.values()), outcomes
    figures = {
        json.dumps({k: r[k] for k in ("t_1", "t_a", "trips", "start")}) for r in results.values()
    }
    assert len(figures) == 1  # every member reports the same run
    first = results[feet[0]]
    start = first["start"]
    print(
        f"\n{len(eyes)} eye-bots, {len(feet)} foot-bots, {DURATION:g} s: t_1 {first['t_1']}, "
        f"t_a {first['t_a']}, {first['trips']} trips, {first['wall_s']:.1f} s wall "
        f"({first['footbot_s_per_wall_s']:.0f} foot-bot-s per wall s)"
    )
    # every foot-bot process ran the foot-bot loop; trips carry simulated times in the run
    trips = [t for f in feet for t in results[f]["me"]["trips"]]
    assert all("trips" in results[f]["me"] for f in feet)
    assert trips, "no foot-bot reached its goal"
    for goal, begin, end in trips:
        assert goal in ("target", "source")
        assert start - 1e-9 <= begin < end <= start + DURATION + 1e-9
    assert first["trips"] == len(trips)
    assert first["t_1"] is not None and 0.0 < first["t_1"] <= DURATION
    # every eye-bot process ran the eye-bot loop; those that saw foot-bots learned
    learned = []
    for e in eyes:
        policy = results[e]["me"]["eyebot"]
        assert len(policy["to_source"]) == len(policy["to_target"]) == 12
        uniform = all(
            math.isclose(p, 1.0 / 12, abs_tol=1e-4)
            for p in policy["to_source"] + policy["to_target"]
        )
        learned.append(not uniform)
        assert uniform or policy["seen"] > 0
    assert sum(learned) >= 2  # at least the eye-bots over the start and over the target


@pytest.mark.timeout(150)
async def test_a_foot_bot_and_an_eye_bot_killed_mid_run_are_left_out(
    mover_up: Any, tmp_path: Path
) -> None:
    up, eyes, feet = await _team(mover_up, tmp_path)
    members = eyes + feet
    running = asyncio.ensure_future(
        launch(
            up.node,
            "stigmergic_navigation",
            members,
            {"duration": DURATION},
            run="k",
            seed=3,
            policy="survivors",
        )
    )
    async with asyncio.timeout(60):  # until the run is under way: 20 simulated seconds in
        while (await up.node.call("world", "status", timeout=5))["tick"] < 200:
            await asyncio.sleep(0.1)
    victims = sorted([feet[1], eyes[4]])
    for victim in victims:
        info = up.node.membership.info(victim)
        assert info is not None
        os.kill(info.pid, signal.SIGKILL)
    outcomes = await asyncio.wait_for(running, 120)
    for victim in victims:
        assert "error" in outcomes[victim] and outcomes[victim].get("result") is None
    results: dict[str, Any] = {m: outcomes[m].get("result") for m in members if m not in victims}
    assert all(r is not None for r in results.values()), outcomes
    kept = ("t_1", "t_a", "trips", "lost")
    assert len({json.dumps({k: r[k] for k in kept}) for r in results.values()}) == 1
    first = results[feet[0]]
    assert first["lost"] == victims and first["footbots"] == len(feet) - 1
    status = await up.node.call("world", "status", timeout=5)
    assert sorted(status["dropped"]) == victims  # the world went on without them
    print(
        f"\n{victims} killed at tick 200: the {len(results)} others finished, "
        f"{first['trips']} trips, t_1 {first['t_1']}"
    )
