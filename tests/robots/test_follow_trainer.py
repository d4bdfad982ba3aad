"""Follow the trainer (section 5): the trainee follows the trainer to every labelled place and
writes one snapshot per place to a JSON-lines dataset."""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
from pathlib import Path

import programs
from mover import ProgramHost, launch
from robots import Robot
from sim_hw import RobotDropped, World, WorldServer, WorldSpec, in_process

from .conftest import Mesh

PLACES = {"door-a": [5.0, 1.0], "door-b": [5.0, 4.0], "door-c": [2.0, 4.0]}


async def test_the_trainee_records_one_snapshot_per_place(mesh: Mesh, tmp_path: Path) -> None:
    world = World(WorldSpec(size=(7.0, 5.5)), seed=2)
    server = WorldServer(world, expect=2)
    ws, *nodes = await mesh(["ws", "trainer", "trainee"])
    poses = {"trainer": [2.0, 1.0, 0.0], "trainee": [1.2, 1.0, 0.0]}
    hws = await asyncio.gather(*(in_process(server, n, {"pose": poses[n]}) for n in poses))
    for node, hw in zip(nodes, hws, strict=True):
        ProgramHost(node, programs.installed(), Robot(node.name, hw, node))
    dataset = tmp_path / "doors.jsonl"
    args = {"trainer": "trainer", "places": PLACES, "dataset": str(dataset)}
    with contextlib.suppress(RobotDropped):
        async with contextlib.AsyncExitStack() as idle:
            for hw in hws:  # an idle robot process keeps ticking a lock-step world
                await idle.enter_async_context(hw.clock.ticking())
            outcomes = await launch(ws, "follow_trainer", ["trainer", "trainee"], args, run="train")
            await server.door.aclose()
    print(f"\nfollow the trainer: {world.time:.1f} s simulated; {outcomes}")
    assert outcomes["trainer"]["result"] == {"places": list(PLACES), "records": 0}
    assert outcomes["trainee"]["result"] == {"places": list(PLACES), "records": 3}
    lines = [json.loads(line) for line in dataset.read_text().splitlines()]
    assert [r["label"] for r in lines] == list(PLACES)
    for record in lines:  # the trainee stood near the place, the trainer in sight ahead
        shot = record["snapshot"]
        assert record["trainee"] == "trainee"
        assert math.dist(shot["odometry"][:2], PLACES[record["label"]]) < 1.2
        assert len(shot["sonar"]) == 8
        assert any(s["id"] == "trainer" for s in shot["camera"])
