"""The grid world server and the grid HAL in one process: no network, no sleeps to speak of."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from experiments.maze import run_trial
from mover import Message, RunTeam
from programs.explore_maze import MazeTeam, explore_maze
from programs.foraging import foraging
from robots import Robot
from robots.grid_hal import FREE, OBSTACLE, OCCUPIED, GridHardware
from sim_hw.grid import (
    Grid,
    GridServer,
    GridWorld,
    RobotDropped,
    generate_maze,
    in_process,
    save_maze,
)
from sim_hw.grid.cli import build_server

EAST, WEST = 1, 3


def corridor_server(**kw: Any) -> GridServer:
    grid = Grid(np.array([[1, 1, 1, 1, 1], [1, 0, 0, 0, 1], [1, 1, 1, 1, 1]]))
    return GridServer(GridWorld(grid, (1, 1)), **kw)


async def test_a_round_waits_for_every_robot_and_applies_actions_in_name_order() -> None:
    server = corridor_server(exclusive=True, expect=2)
    a, _b = await asyncio.gather(
        server.door.join("a", {"start": [1, 1]}), server.door.join("b", {"start": [1, 3]})
    )
    assert a["readings"]["round"] == 0 and a["readings"]["hears"] == ["b"]
    assert [n[1] for n in a["readings"]["around"]] == [OBSTACLE, FREE, OBSTACLE, OBSTACLE]
    step_a = asyncio.ensure_future(server.door.step("a", 0, {"move": EAST, "value": 7}))
    await asyncio.sleep(0)
    assert not step_a.done() and server.round == 0
    ra, rb = await asyncio.gather(step_a, server.door.step("b", 0, {"move": WEST}))
    # a moved first into the middle cell; b's move into it then failed
    assert ra["moved"] and not rb["moved"] and server.round == 1
    assert server.world.marks[server.grid.index((1, 1))] == 7
    assert ra["around"][EAST][1] == OCCUPIED
    again = await server.door.step("a", 0, {"move": EAST})  # a retry of a done round
    assert again is ra


@pytest.mark.parametrize("turns", ["together", "sequential"])
async def test_a_cancelled_step_does_not_fail_its_retry(turns: str) -> None:
    server = corridor_server(expect=2, turns=turns)
    await asyncio.gather(server.door.join("a", {}), server.door.join("b", {}))
    given_up = asyncio.ensure_future(server.door.step("a", 0, {}))
    await asyncio.sleep(0)
    retry = asyncio.ensure_future(server.door.step("a", 0, {}))
    await asyncio.sleep(0)
    given_up.cancel()  # the caller gave the first call up; its retry must not lose the round
    await asyncio.sleep(0)
    await server.door.step("b", 0, {})
    assert (await asyncio.wait_for(retry, 2))["round"] == 1
    assert given_up.cancelled()


async def test_a_silent_robot_is_dropped_after_the_timeout(
    caplog: pytest.LogCaptureFixture,
) -> None:
    server = corridor_server(expect=2, timeout=0.05)
    await asyncio.gather(server.door.join("a", {}), server.door.join("b", {}))
    with caplog.at_level(logging.WARNING, logger="sim_hw.grid._server"):
        reply = await asyncio.wait_for(server.door.step("a", 0, {}), 2)
    assert reply["round"] == 1 and server.door.dropped == ["b"]
    assert "robot b sent no action for round 0" in caplog.text
    with pytest.raises(RobotDropped):
        await server.door.step("b", 0, {})


class _Bus:
    """In-process stand-ins for the node's broadcast, subscriptions and membership view."""

    def __init__(self, names: list[str]) -> None:
        self.queues: dict[str, asyncio.Queue[Message]] = {n: asyncio.Queue() for n in names}
        self.values: dict[str, Any] = {}
        self.all_in = asyncio.Event()
        self.members = sorted(names)


class _Inbox:
    def __init__(self, queue: asyncio.Queue[Message]) -> None:
        self.queue = queue

    async def get(self, timeout: float | None = None) -> Message:
        return await asyncio.wait_for(self.queue.get(), timeout)

    async def __aenter__(self) -> _Inbox:
        return self

    async def __aexit__(self, *exc: object) -> None:
        pass


class _Node:
    """A :class:`MazeNode` on the bus: everyone hears all (the world says who is in range)."""

    def __init__(self, bus: _Bus, name: str) -> None:
        self.bus, self.name, self.membership = bus, name, set(bus.members)

    def subscribe(self, topic: str) -> _Inbox:
        return _Inbox(self.bus.queues[self.name])

    async def broadcast(
        self, topic: str, data: Any, *, range: float | None = None, reliable: bool = False
    ) -> None:
        for name, queue in self.bus.queues.items():
            if name != self.name:
                queue.put_nowait(Message(self.name, topic, data, None, None, 0.0))


class _Team:
    """A :class:`MazeTeam` on the bus: its ``and`` step waits for every member's value."""

    def __init__(self, bus: _Bus, me: str) -> None:
        self.bus, self.me, self.members, self.run, self.seed = bus, me, bus.members, "test", 0
        self.node = _Node(bus, me)

    async def distributed_and(self, operation: Callable[[], Awaitable[Any]]) -> dict[str, Any]:
        self.bus.values[self.me] = await operation()
        if len(self.bus.values) == len(self.members):
            self.bus.all_in.set()
        await self.bus.all_in.wait()
        return dict(self.bus.values)


def _a_run_team_is_a_maze_team(team: RunTeam) -> MazeTeam:
    """What the programs ask of a team, a real one has (mypy checks this)."""
    return team


Program = Callable[..., Awaitable[dict[str, Any]]]
"""A grid program: ``program(robot, team, **args)``."""


async def _run_team(
    server: GridServer,
    names: list[str],
    specs: list[dict[str, Any]],
    program: Program,
    **args: Any,
) -> list[dict[str, Any]]:
    hws = await asyncio.gather(
        *(in_process(server, n, s) for n, s in zip(names, specs, strict=True))
    )

    async def idle(hw: GridHardware) -> None:
        while True:
            await hw.clock.tick()

    idles = [asyncio.ensure_future(idle(hw)) for hw in hws]
    bus = _Bus(names)
    teams: list[MazeTeam] = [_Team(bus, n) for n in names]  # what the programs ask of a team
    try:
        return list(
            await asyncio.gather(
                *(
                    program(Robot(n, hw), team, **args)
                    for n, hw, team in zip(names, hws, teams, strict=True)
                )
            )
        )
    finally:
        for task in idles:
            task.cancel()
        await asyncio.gather(*idles, return_exceptions=True)


@pytest.mark.parametrize(
    ("size", "p", "seed", "method"),
    [(15, 0.85, 1, "cu_lvp"), (20, 0.15, 3, "cu_lvp"), (15, 0.5, 4, "nf")],
)
async def test_maze_rounds_match_the_in_process_runner(
    tmp_path: Path, size: int, p: float, seed: int, method: str
) -> None:
    maze = generate_maze(size, p, np.random.default_rng(seed), n_starts=4)
    save_maze(tmp_path / "m.json", maze)
    ref = run_trial(maze, 4, method.replace("_", "-"), np.random.SeedSequence(seed))
    server = build_server(str(tmp_path / "m.json"), {}, expect=4)
    names = ["a", "b", "c", "d"]
    starts = [list(s) for s in maze.starts[:4]]
    out = await _run_team(
        server,
        names,
        [{"start": s} for s in starts],
        explore_maze,
        method=method,
        seed=seed,
        starts=starts,
        shape=list(maze.shape),
    )
    assert {o["rounds"] for o in out} == {ref["rounds"]}
    assert sum(o["moves"] for o in out) == ref["cost"]


async def test_foraging_in_process_finishes(tmp_path: Path) -> None:
    (tmp_path / "g.txt").write_text(
        "........\n..R.....\n........\n....B...\n........\n.#......\n......R.\n........\n"
    )
    server = build_server(str(tmp_path / "g.txt"), {}, expect=3)
    server.world.resources = [q * 200 for q in server.world.resources]
    server.world.remaining = sum(server.world.resources)
    out = await _run_team(
        server, ["x", "y", "z"], [{"view": 0}] * 3, foraging, method="marking", seed=2
    )
    assert all(o["finished"] for o in out) and server.world.remaining == 0
    text = server.snapshot_text()
    assert text.startswith("round ") and "remaining 0" in text


@pytest.mark.parametrize(
    ("size", "n", "quantity", "seed", "method"),
    [(12, 4, 300, 1, "cmarking"), (12, 3, 300, 4, "ants")],
)
async def test_sequential_turns_repeat_the_in_process_foraging_run(
    tmp_path: Path, size: int, n: int, quantity: int, seed: int, method: str
) -> None:
    from experiments.foraging import Setup, run_trial
    from sim_hw.grid import place_resources, random_obstacles
    from tests.programs._grid import write_grid

    env_seed, agent_seed = (seed, 1, 0), (seed, 1, 0, n, 0)
    trial = run_trial(Setup(size, 0.05, 2, quantity), n, method, env_seed, agent_seed, 20000)
    env = np.random.default_rng(np.random.SeedSequence(list(env_seed)))
    base = (size // 2, size // 2)
    grid = random_obstacles(size, size, 0.05, env, keep_free=(base,))
    resources = place_resources(grid, 2, quantity, env, exclude=(base,))
    path = write_grid(tmp_path / "field.json", grid.obstacles, base, resources)
    server = build_server(str(path), {"pheromone": method == "ants"}, expect=n, turns="sequential")
    out = await _run_team(
        server,
        [f"r{i}" for i in range(n)],
        [{"view": 0}] * n,
        foraging,
        method=method,
        seed=list(agent_seed),
    )
    assert trial.finished and {o["rounds"] for o in out} == {trial.iterations}
