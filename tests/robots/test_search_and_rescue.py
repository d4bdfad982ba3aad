"""The whole search-and-rescue program (Figure 3) with three robots in one process: three
robot nodes and a workstation over zenoh on loopback, the demo world in lock-step, the program
launched by name from the workstation (Figure 2: WS and the robots)."""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from typing import Any

import pytest

import programs
from mover import ProgramHost, launch
from robots import Robot
from sim_hw import RobotDropped, World, WorldServer, WorldSpec, in_process

from .conftest import NAMES, Mesh


@pytest.mark.parametrize("seed", [3, 4, 7])
async def test_three_robots_find_gather_and_move_the_box(
    demo: WorldSpec, mesh: Mesh, seed: int
) -> None:
    world = World(demo, seed=seed)
    server = WorldServer(world, expect=len(NAMES))
    ws, *nodes = await mesh(["ws", *NAMES])
    hws = await asyncio.gather(*(in_process(server, n) for n in NAMES))
    for node, hw in zip(nodes, hws, strict=True):
        ProgramHost(node, programs.installed(), Robot(node.name, hw, node))
    reports: list[tuple[float, float, str, str]] = []
    start = time.perf_counter()
    sub = ws.subscribe("mover/run/sr")  # progress, as the workstation sees it

    async def listen() -> None:
        async for m in sub:
            reports.append(
                (world.time, time.perf_counter() - start, m.data["member"], m.data["phase"])
            )

    listener = asyncio.ensure_future(listen())
    goal = next(m.center for m in demo.markers if m.id == "goal")
    box0 = world.box_pose("victim")
    path = [[goal[0] - box0[0], goal[1] - box0[1]]]
    with contextlib.suppress(RobotDropped):  # the world closes under the idle robots
        async with contextlib.AsyncExitStack() as idle:
            for hw in hws:  # what an idle robot process does in a lock-step world: keep ticking
                await idle.enter_async_context(hw.clock.ticking())
            outcomes = await launch(
                ws, "search_and_rescue", list(NAMES), {"path": path, "seed": seed}, run="sr"
            )
            wall = time.perf_counter() - start
            sim = world.time
            await server.door.aclose()
    await asyncio.sleep(0.2)  # the last reports
    listener.cancel()
    await asyncio.gather(listener, return_exceptions=True)
    box = world.box_pose("victim")
    along = ((box[0] - box0[0]) * path[0][0] + (box[1] - box0[1]) * path[0][1]) / math.hypot(
        *path[0]
    )
    print(
        f"\nsearch and rescue: {sim:.1f} s simulated, {wall:.1f} s wall; the box moved "
        f"{math.dist(box[:2], box0[:2]):.2f} m ({along:.2f} m along the path), "
        f"to ({box[0]:.2f}, {box[1]:.2f}) for a goal at {goal}"
    )
    for t, w, member, phase in sorted(reports):
        print(f"  sim {t:6.1f} s  wall {w:5.2f} s  {member:8s} {phase}")
    for name, out in outcomes.items():
        print(f"  {name}: {out.get('result', out)}")
    results: list[dict[str, Any]] = [o["result"] for o in outcomes.values() if "result" in o]
    assert len(results) == len(NAMES), outcomes
    assert len({r["winner"] for r in results}) == 1
    assert sorted(r["role"] for r in results) == ["pusher", "steerer", "steerer"]
    assert {p for *_, p in reports} >= {"searching", "found", "gathering", "pushing", "done"}
    assert along >= 2.0
    assert not server.door.dropped
