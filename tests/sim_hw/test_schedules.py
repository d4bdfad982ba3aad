"""The door's schedules where the door tests do not reach: commands handed in by frame (no one
waits on a future), the sequential schedule's demand on its stepper, hooks told every tick."""

from __future__ import annotations

import asyncio
from collections.abc import Mapping
from typing import Any

import numpy as np
import pytest

from sim_hw import World, random_obstacles
from sim_hw._lockstep import Command, LockstepDoor
from sim_hw.continuous._stepper import WorldStepper
from sim_hw.grid import Grid, GridServer, GridWorld

EAST = 1


def corridor(**kw: Any) -> GridServer:
    grid = Grid(np.array([[1, 1, 1, 1, 1, 1], [1, 0, 0, 0, 0, 1], [1, 1, 1, 1, 1, 1]]))
    return GridServer(GridWorld(grid, (1, 1)), **kw)


async def test_a_command_by_frame_leaves_no_future_and_a_retry_is_answered_at_once() -> None:
    server = corridor(expect=2)
    told: list[Mapping[str, Command]] = []
    server.door.on_tick.append(told.append)
    await asyncio.gather(
        server.door.join("a", {"start": [1, 1]}), server.door.join("b", {"start": [1, 4]})
    )
    assert server.door.hand_in("a", 0, {"move": EAST}) is None
    assert server.door.waiter_of("a") is None and server.round == 0  # waits for b; nothing awaits a
    assert server.door.hand_in("b", 0, {}) is None  # the last command: the round runs
    assert server.round == 1 and told == [{"a": {"move": EAST}, "b": {}}]
    retry = server.door.hand_in("a", 0, {"move": EAST})  # its frame was lost: the readings after 0
    assert retry is not None and retry["round"] == 1 and server.robots["a"].moves == 1
    await server.door.aclose()


async def test_a_silent_frame_robot_is_timed_like_a_caller() -> None:
    server = corridor(expect=2, timeout=0.05)
    await asyncio.gather(server.door.join("a", {}), server.door.join("b", {}))
    server.door.hand_in("a", 0, {})
    await asyncio.sleep(0.2)
    assert server.door.dropped == ["b"] and server.round == 1  # b was dropped, the round went on
    await server.door.aclose()


async def test_sequential_turns_need_a_stepper_that_takes_turns() -> None:
    with pytest.raises(TypeError, match="cannot take sequential turns"):
        LockstepDoor(WorldStepper(World(random_obstacles((4.0, 4.0), 0))), turns="sequential")
    assert corridor(turns="sequential").door.turns == "sequential"


async def test_real_time_ticks_without_waiting_and_the_latest_command_stands() -> None:
    door = LockstepDoor(WorldStepper(World(random_obstacles((4.0, 4.0), 0))), speed=20.0)
    await door.join("a")
    assert not door.lockstep
    door.submit("a", 0, {"v": 0.1, "w": 0.0})
    door.submit("a", 0, {"v": 0.2, "w": 0.0})  # in real time the latest stands
    readings = await asyncio.wait_for(door.step("a", 0, {"v": 0.3, "w": 0.0}), 2)
    assert readings["tick"] >= 1 and door.stepper.world.robots["a"].v == pytest.approx(0.3)
    await door.aclose()
