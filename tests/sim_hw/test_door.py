"""The lock-step door's idle set, first-command-wins, silence, and the robot clock over it.

In one process (no network): the door is driven directly, or through the HALs of
``sim_hw.in_process`` / ``sim_hw.grid.in_process``.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from typing import Any

import numpy as np
import pytest

from sim_hw import RobotDropped, World, WorldServer, in_process, random_obstacles
from sim_hw.grid import Grid, GridServer, GridWorld
from sim_hw.grid import in_process as grid_in_process

EAST, WEST = 1, 3


def corridor(**kw: Any) -> GridServer:
    grid = Grid(np.array([[1, 1, 1, 1, 1, 1], [1, 0, 0, 0, 0, 1], [1, 1, 1, 1, 1, 1]]))
    return GridServer(GridWorld(grid, (1, 1)), **kw)


async def test_an_idle_robot_is_not_waited_for_and_keeps_its_readings() -> None:
    server = corridor(expect=2)
    await asyncio.gather(
        server.door.join("a", {"start": [1, 1]}), server.door.join("b", {"start": [1, 4]})
    )
    assert server.door.idle("b", {})["round"] == 0
    for n in range(3):
        got = await asyncio.wait_for(server.door.step("a", n, {"move": EAST}), 1)
        assert got["round"] == n + 1
    assert server.stepper.readings("b")["round"] == 3  # sensed with the others
    assert server.robots["b"].moves == 0 and server.robots["a"].moves == 3  # b stood still
    assert server.door.status()["idle"] == ["b"]
    assert server.door.wake("b")["round"] == 3
    stepping = asyncio.ensure_future(server.door.step("a", 3, {}))
    await asyncio.sleep(0.01)
    assert not stepping.done()  # now the round waits for b again
    await server.door.step("b", 3, {"move": WEST})
    assert (await stepping)["round"] == 4


async def test_a_world_whose_robots_are_all_idle_holds_still() -> None:
    server = corridor(expect=2)
    await asyncio.gather(server.door.join("a", {}), server.door.join("b", {}))
    server.door.idle("a", {})
    server.door.idle("b", {})
    await asyncio.sleep(0.05)
    assert server.round == 0 and server.door._deadline is None  # no tick, no timer
    joined = await asyncio.wait_for(server.door.join("c", {}), 1)  # a tick boundary: placed at once
    assert joined["readings"]["round"] == 0
    server.door.idle("c", {})
    assert server.round == 0
    server.door.wake("a")
    await server.door.step("a", 0, {})
    assert server.round == 1


async def test_the_first_command_for_a_tick_is_the_one_used() -> None:
    server = corridor(expect=2)
    await asyncio.gather(
        server.door.join("a", {"start": [1, 2]}), server.door.join("b", {"start": [1, 4]})
    )
    first = server.door.submit("a", 0, {"move": EAST})
    retry = server.door.submit("a", 0, {"move": WEST})  # a retry, never a replacement
    assert retry is first
    await server.door.step("b", 0, {})
    assert (await first)["round"] == 1
    assert server.grid.cell(server.robots["a"].cell) == (1, 3)  # moved east


@pytest.mark.parametrize("turns", ["together", "sequential"])
async def test_a_command_from_an_idle_robot_wakes_it(turns: str) -> None:
    server = corridor(expect=2, turns=turns)
    await asyncio.gather(server.door.join("a", {}), server.door.join("b", {}))
    server.door.idle("a", {})
    waiter = server.door.submit("a", 0, {})
    assert server.door.status()["idle"] == []
    await server.door.step("b", 0, {})
    assert (await asyncio.wait_for(waiter, 1))["round"] in (0, 1)  # sequential: a's next turn


async def test_sequential_turns_skip_idle_robots() -> None:
    server = corridor(expect=3, turns="sequential")
    await asyncio.gather(*(server.door.join(n, {}) for n in "abc"))
    server.door.idle("b", {})

    async def turns(robot: str) -> None:  # each robot on its own, as processes are
        for n in range(3):
            await server.door.step(robot, n, {})
        server.door.idle(robot, {})  # then idle: the others' turns do not wait for it

    await asyncio.wait_for(asyncio.gather(turns("a"), turns("c")), 2)
    assert server.round == 3 and server.door.status()["idle"] == ["a", "b", "c"]
    still = server.round
    await asyncio.sleep(0.05)
    assert server.round == still
    assert server.door.wake("b")["round"] == still


async def test_joins_wait_for_expect_even_when_those_in_are_idle() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2)
    joining = asyncio.ensure_future(server.door.join("a"))  # the pymunk world admits early
    await asyncio.sleep(0)
    server.door.idle("a", {"v": 0.0, "w": 0.0, "push": None})  # (its join is answered at the start)
    assert server.door.status()["started"] is False and not joining.done()
    await server.door.join("b")
    assert server.door.status()["started"] is True
    await asyncio.wait_for(joining, 1)
    for n in range(5):
        await asyncio.wait_for(server.door.step("b", n, {"v": 0.2, "w": 0.0}), 1)
    assert server.world.tick == 5 and server.world.robots["a"].v == 0.0


async def test_without_drop_silent_a_silent_robot_is_waited_for(
    caplog: pytest.LogCaptureFixture,
) -> None:
    server = corridor(expect=2, timeout=0.05)
    server.door.drop_silent = False  # as a world process has it: liveness decides
    await asyncio.gather(server.door.join("a", {}), server.door.join("b", {}))
    caplog.set_level(logging.WARNING, logger="sim_hw.lockstep")
    stepping = asyncio.ensure_future(server.door.step("a", 0, {}))
    await asyncio.sleep(0.3)
    assert not stepping.done() and server.door.dropped == []
    assert caplog.text.count("waiting for robot b: round 0") == 1  # said once
    await server.door.step("b", 0, {})
    assert (await stepping)["round"] == 1


async def test_the_clock_idles_and_wakes() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2)
    a, b = await asyncio.gather(in_process(server, "a"), in_process(server, "b"))
    a.drive.set_velocity(0.3, 0.0)
    await asyncio.gather(a.clock.tick(), b.clock.tick())
    async with a.clock.idling():
        with pytest.raises(RuntimeError, match="idle"):
            await a.clock.tick()
        await b.clock.sleep(1.0)  # ten ticks without a
        assert server.world.robots["a"].v == 0.0  # the drive stopped
        assert a.clock.now() == pytest.approx(b.clock.now())  # a's readings kept up
    ticking = asyncio.ensure_future(b.clock.tick())
    await asyncio.sleep(0.01)
    assert not ticking.done()  # the world waits for a again
    await a.clock.tick()
    await ticking
    assert server.world.tick == 12


async def test_a_cancelled_tick_finishes_in_the_background_and_the_next_takes_it() -> None:
    """The world never sees half a tick, and the readings change only in the robot's own
    calls: a tick whose caller was cancelled ends in the background, and the robot's next
    tick takes its readings (handing in nothing: that tick's command went in already)."""
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2)
    a, b = await asyncio.gather(in_process(server, "a"), in_process(server, "b"))
    a.drive.set_velocity(0.3, 0.0)
    given_up = asyncio.ensure_future(a.clock.tick())
    await asyncio.sleep(0.01)
    given_up.cancel()
    a.drive.set_velocity(0.0, 1.0)  # goes with a's next command (tick 1), not a second for 0
    await b.clock.tick()  # tick 0: a's first command
    await asyncio.sleep(0.01)
    assert server.world.tick == 1
    assert server.world.robots["a"].v == pytest.approx(0.3)
    assert a.clock.now() == 0.0  # the world answered; a has not asked yet
    await asyncio.wait_for(a.clock.tick(), 1)  # takes tick 0's readings at once
    assert a.clock.now() == pytest.approx(0.1) and server.world.tick == 1
    await asyncio.gather(a.clock.tick(), b.clock.tick())
    assert server.world.tick == 2 and server.world.robots["a"].w == pytest.approx(1.0)
    assert a.clock.now() == pytest.approx(0.2)


async def test_passed_returns_once_a_command_went_in_after_the_time() -> None:
    server = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=1)
    a = await in_process(server, "a")
    waiting = asyncio.ensure_future(a.clock.passed(0.25))
    await a.clock.sleep(0.3)  # commands handed in at t = 0, 0.1, 0.2
    assert not waiting.done()
    await a.clock.tick()  # at t = 0.3
    await asyncio.wait_for(waiting, 1)
    await a.clock.passed(0.3)  # it went on past 0.3 (a command handed in then): at once
    await a.clock.passed(0.0)  # already: at once
    lost = asyncio.ensure_future(a.clock.passed(math.inf))
    await asyncio.sleep(0.01)
    await server.door.leave("a")
    with pytest.raises(RobotDropped):
        await a.clock.tick()
    with pytest.raises(RobotDropped):
        await asyncio.wait_for(lost, 1)


async def test_an_idle_robot_learns_that_it_was_dropped() -> None:
    server = corridor(expect=1)
    hw = await grid_in_process(server, "a", {})
    idle_since = time.monotonic()

    async def idle() -> None:
        async with hw.clock.idling():
            asyncio.get_running_loop().call_later(0.05, server.door.drop, "a", "left the team")
            await hw.clock.passed(math.inf)

    with pytest.raises(RobotDropped):
        await asyncio.wait_for(idle(), 1)
    assert time.monotonic() - idle_since < 1.0


async def test_owned_stays_until_its_round_by_itself() -> None:
    server = corridor(expect=2)
    a, b = await asyncio.gather(grid_in_process(server, "a", {}), grid_in_process(server, "b", {}))

    async def run(hw: Any) -> int:
        async with hw.clock.owned(at=3):
            hw.drive.move(EAST)
            await hw.clock.tick()
            return int(hw.clock.now())

    assert list(await asyncio.wait_for(asyncio.gather(run(a), run(b)), 2)) == [4, 4]
