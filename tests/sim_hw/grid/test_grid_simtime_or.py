"""A grid team's ``distributed_or`` in simulated time: the grid world and the robots' HALs in
this process, their nodes over zenoh on loopback, each member's run clock the robot process's
``HostClock`` over its grid clock (which must hold a member past the earliest finish)."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import AsyncExitStack

import numpy as np
import pytest_asyncio

from mover import Node, NodeConfig, Outcome, RunTeam, TeamCredentials
from mover._config import free_port
from robots.grid_hal import GridHardware
from robots.hal import HardwareLost
from robots.process import HostClock
from sim_hw.grid import Grid, GridServer, GridWorld, in_process

NAMES = ("a", "b", "c")


@pytest_asyncio.fixture
async def nodes() -> AsyncIterator[list[Node]]:
    """One node per robot, in one team over zenoh on loopback."""
    team = TeamCredentials.generate("grid")
    port = free_port()
    async with AsyncExitStack() as stack:
        out = [
            await stack.enter_async_context(
                Node(
                    name,
                    team,
                    config=NodeConfig(listen=(f"tcp/127.0.0.1:{port}",))
                    if i == 0
                    else NodeConfig(connect=(f"tcp/127.0.0.1:{port}",)),
                )
            )
            for i, name in enumerate(NAMES)
        ]
        for node in out:
            await node.membership.wait_for(set(NAMES), timeout=10)
        yield out


def _walk(hw: GridHardware, until: int, wall_after: float = 0.0) -> Callable[[], Awaitable[int]]:
    """Hand in (empty) actions until round ``until``; then, ``wall_after`` wall seconds later
    (handing in nothing: the lock-step world waits), return that round."""

    async def op() -> int:
        while hw.clock.now() < until:
            await hw.clock.tick()
        await asyncio.sleep(wall_after)
        return hw.clock.now()

    return op


async def test_a_grid_team_decides_its_or_in_rounds_and_goes_on(nodes: list[Node]) -> None:
    """b finishes at round 3 and claims half a wall second later; a and c have gone past round
    3 by then and are held there until the decision. b wins on every member, and the next OR
    runs on from where the first stopped (the hold was lifted): a three-way tie at round 6
    goes to the first by name."""
    server = GridServer(GridWorld(Grid(np.zeros((5, 5), dtype=bool)), (2, 2)), expect=3)
    hws = await asyncio.gather(
        *(in_process(server, n, {"start": [0, i]}) for i, n in enumerate(NAMES))
    )
    lost: asyncio.Future[HardwareLost] = asyncio.get_running_loop().create_future()
    clocks = [HostClock(hw, lost) for hw in hws]
    teams = [
        RunTeam(node, "or-in-rounds", NAMES, clock=clock)
        for node, clock in zip(nodes, clocks, strict=True)
    ]
    try:
        ends = {"a": 5, "b": 3, "c": 8}
        first: list[Outcome] = await asyncio.wait_for(
            asyncio.gather(
                *(
                    t.distributed_or(_walk(hw, ends[t.me], 0.5 if t.me == "b" else 0.0))
                    for t, hw in zip(teams, hws, strict=True)
                )
            ),
            20,
        )
        assert {(o.winner, o.result) for o in first} == {("b", 3)}
        second: list[Outcome] = await asyncio.wait_for(
            asyncio.gather(
                *(t.distributed_or(_walk(hw, 6)) for t, hw in zip(teams, hws, strict=True))
            ),
            20,
        )
        assert {(o.winner, o.result) for o in second} == {("a", 6)}
        assert not lost.done()
    finally:
        for clock in clocks:
            await clock.aclose()
        await server.aclose()
