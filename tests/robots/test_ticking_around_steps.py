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
    # in-process robots are never silent for long unless the machine is loaded: no drops
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=len(NAMES), timeout=60)
    lost: asyncio.Future[HardwareLost] = asyncio.get_running_loop().create_future()
    async with team_nodes(NAMES, "ticking") as nodes:
        hws = await asyncio.gather(*(in_process(server, n) for n in NAMES))
        clocks = [HostClock(hw, lost) for hw in hws]
        ends = {"a": (1.0, 0.5), "b": (2.0, 1.5)}  # simulated seconds: OR, then AND

        async def member(
            team: RunTeam, hw: Hardware, clock: HostClock
        ) -> tuple[str, dict[str, float], list[float]]:
            first, second = ends[team.me]
            async with hw.clock.ticking():  # the earlier README's advice
                won = await team.distributed_or(_walk(hw, first))
            after = [hw.clock.now()]
            async with hw.clock.ticking():
                got: dict[str, float] = await team.distributed_and(_walk(hw, second))
            after.append(hw.clock.now())
            clock.release()  # the run is over: idle (as a robot process does)
            return won.winner, got, after

        try:
            teams = [
                RunTeam(node, "ticking", NAMES, clock=clock)
                for node, clock in zip(nodes, clocks, strict=True)
            ]
            with caplog.at_level(logging.WARNING, logger="sim_hw.hardware"):
                runs = (member(*m) for m in zip(teams, hws, clocks, strict=True))
                results = await asyncio.wait_for(asyncio.gather(*runs), 20)
        finally:
            for clock in clocks:
                await clock.aclose()
            await server.door.aclose()
    assert [winner for winner, _, _ in results] == ["a", "a"]
    ands = [got for _, got, _ in results]
    assert ands[0] == ands[1]
    assert ands[0]["b"] == pytest.approx(1.5)  # b walked on to its own end
    # Where each goes on from is fixed in simulated time, background ticks and all: a step
    # holds (or idles) its members from where their operations ended until all are done, and
    # the background ticks pause meanwhile. After the OR, the winner a reads its finish
    # (1.0 s); the loser b had handed in its command for that tick, and the block's end waits
    # for its readings (1.1 s). After the AND both read the last finish (1.5 s).
    assert [after for _, _, after in results] == [[1.0, 1.5], [1.1, 1.5]]
    assert not lost.done()
    paused = [r for r in caplog.records if "pauses while a team step idles" in r.message]
    assert paused, "the pause is said in the log"
    assert len({r.message for r in paused}) == len(paused)  # once a robot
