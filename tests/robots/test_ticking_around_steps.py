"""A program written to the earlier README: ``clock.ticking()`` kept around team steps in
simulated time. The steps idle the clock while a member waits for the others; the background
ticks pause meanwhile (said once in the log) instead of failing the program (issue 22)."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable

import pytest

from mover import RunTeam
from robots.hal import Hardware, HardwareLost
from robots.process import HostClock
from sim_hw import World, WorldServer, in_process, random_obstacles
from tests.helpers.loopback import team_nodes

NAMES = ("a", "b")


def _walk(hw: Hardware, until: float) -> Callable[[], Awaitable[float]]:
    """Tick until simulated time ``until``; return the time then."""

    async def op() -> float:
        while hw.clock.now() < until - 1e-9:
            await hw.clock.tick()
        return hw.clock.now()

    return op


async def test_ticking_around_an_or_and_an_and_runs(caplog: pytest.LogCaptureFixture) -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=len(NAMES))
    lost: asyncio.Future[HardwareLost] = asyncio.get_running_loop().create_future()
    async with team_nodes(NAMES, "ticking") as nodes:
        hws = await asyncio.gather(*(in_process(server, n) for n in NAMES))
        clocks = [HostClock(hw, lost) for hw in hws]
        ends = {"a": (1.0, 0.5), "b": (2.0, 1.5)}  # simulated seconds: OR, then AND

        async def member(team: RunTeam, hw: Hardware) -> tuple[str, dict[str, float]]:
            first, second = ends[team.me]
            async with hw.clock.ticking():  # the earlier README's advice
                won = await team.distributed_or(_walk(hw, first))
            async with hw.clock.ticking():
                got: dict[str, float] = await team.distributed_and(_walk(hw, second))
            return won.winner, got

        try:
            teams = [
                RunTeam(node, "ticking", NAMES, clock=clock)
                for node, clock in zip(nodes, clocks, strict=True)
            ]
            with caplog.at_level(logging.WARNING, logger="sim_hw.hardware"):
                results = await asyncio.wait_for(
                    asyncio.gather(*(member(t, hw) for t, hw in zip(teams, hws, strict=True))),
                    20,
                )
        finally:
            for clock in clocks:
                await clock.aclose()
            await server.door.aclose()
    assert [winner for winner, _ in results] == ["a", "a"]
    ands = [got for _, got in results]
    assert ands[0] == ands[1]
    assert ands[0]["b"] == pytest.approx(1.5)  # b walked on to its own end
    assert not lost.done()
    paused = [r for r in caplog.records if "pauses while a team step idles" in r.message]
    assert paused, "the pause is said in the log"
    assert len({r.message for r in paused}) == len(paused)  # once a robot
