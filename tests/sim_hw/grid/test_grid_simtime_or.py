"""A grid team's ``distributed_or`` in simulated time: the grid world and the robots' HALs in
this process, their nodes over zenoh on loopback, each member's run clock the robot process's
``HostClock`` over its grid clock (which must hold a member past the earliest finish)."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Awaitable, Callable

import numpy as np
import pytest
import pytest_asyncio

from mover import Node, Outcome, RunTeam
from robots.grid_hal import GridHardware
from robots.hal import HardwareLost
from robots.process import HostClock
from sim_hw.grid import Grid, GridServer, GridWorld, in_process
from tests.helpers.loopback import team_nodes

NAMES = ("a", "b", "c")


@pytest_asyncio.fixture
async def nodes() -> AsyncIterator[list[Node]]:
    """One node per robot, in one team over zenoh on loopback."""
    async with team_nodes(NAMES, "grid") as out:
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


@pytest_asyncio.fixture
async def grid_team(nodes: list[Node]) -> AsyncIterator[tuple[list[RunTeam], list[GridHardware]]]:
    """The three robots in a 5x5 grid world in this process, each a member of one run whose
    clock is the robot process's ``HostClock`` over its grid clock; no hardware lost at the end."""
    # timeout: in-process robots are silent for long only on a loaded machine (no drops then)
    world = GridWorld(Grid(np.zeros((5, 5), dtype=bool)), (2, 2))
    server = GridServer(world, expect=3, timeout=60)
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
        yield teams, hws
        assert not lost.done()
    finally:
        for clock in clocks:
            await clock.aclose()
        await server.door.aclose()


async def test_a_grid_team_decides_its_or_in_rounds_and_goes_on(
    grid_team: tuple[list[RunTeam], list[GridHardware]],
) -> None:
    """b finishes at round 3 and claims half a wall second later; a and c have gone past round
    3 by then and are held there until the decision. b wins on every member, and the next OR
    runs on from where the first stopped (the hold was lifted): a three-way tie at round 6
    goes to the first by name."""
    teams, hws = grid_team
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
        asyncio.gather(*(t.distributed_or(_walk(hw, 6)) for t, hw in zip(teams, hws, strict=True))),
        20,
    )
    assert {(o.winner, o.result) for o in second} == {("a", 6)}


@pytest.mark.parametrize(("winner", "late"), [("b", "winner"), ("b", "losers"), ("a", "nobody")])
async def test_after_an_or_every_member_reads_the_round_it_stopped_at(
    grid_team: tuple[list[RunTeam], list[GridHardware]], winner: str, late: str
) -> None:
    """The winner finishes at round 3. A loser hands in its action for round 3 before it is
    held; the world takes it once the winner acts again, which may come before or after the
    loser reads its sensors, and (for a winner that is the designated member, "a") before the
    loser has even heard the decision. Either way every member reads round 3 after the OR,
    and its next tick brings round 4 (a loser's action for round 3 went in already). The
    winner, or the losers, are half a wall second late, or nobody is; before, the losers read
    3 or 4 by which came first, and the demo's runs under load parted there (issue 22)."""
    teams, hws = grid_team
    ends = {"a": 5, "b": 8, "c": 8, winner: 3}
    read: dict[str, list[int]] = {}

    async def member(team: RunTeam, hw: GridHardware) -> str:
        outcome: Outcome = await team.distributed_or(_walk(hw, ends[team.me]))
        won = team.me == outcome.winner
        if late != "nobody" and won == (late == "winner"):
            await asyncio.sleep(0.5)  # slow to go on (a loaded machine, a long report)
        read[team.me] = [hw.clock.now()]
        await hw.clock.tick()
        read[team.me].append(hw.clock.now())
        return outcome.winner

    winners = await asyncio.wait_for(
        asyncio.gather(*(member(t, hw) for t, hw in zip(teams, hws, strict=True))), 20
    )
    assert winners == [winner] * 3
    assert read == {"a": [3, 4], "b": [3, 4], "c": [3, 4]}
