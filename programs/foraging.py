"""Foraging as robot processes on a grid world (Simonin et al., INRIA RR-6171, 2007).

Every member runs the same behaviour object the in-process runner uses
(``robots.foraging``: c-marking, marking or ants), one per process: each round it perceives its
cell and its 4 neighbours through the grid HAL, and its action (write the cell, load, unload,
drop pheromone, move) goes back to the world. The floor cells are the shared marks, as an RFID
floor would hold them; robots never exchange messages. The run ends when the world's observer
says the resources are exhausted (or ``max_rounds`` is reached).
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from robots import Robot
from robots.foraging import (
    Action,
    AntAgent,
    AntNeighbour,
    AntPerception,
    CMarkingAgent,
    ForagingMarkingAgent,
    Neighbour,
    Perception,
)
from robots.grid_hal import OBSTACLE, GridHardware, Near

#: Rounds between the agreed start and the latest member's round when the team agreed on it.
START_LEAD = 50

METHODS = ("cmarking", "marking", "ants")


class GridTeam(Protocol):
    """What the grid programs ask of their team: a :class:`mover.RunTeam` is one (a test may
    hand in a stand-in that needs no network)."""

    @property
    def members(self) -> Sequence[str]:
        """Every member's name."""

    @property
    def seed(self) -> int:
        """The run's seed."""

    async def distributed_and(self, operation: Callable[[], Awaitable[Any]]) -> Mapping[str, Any]:
        """Run ``operation`` on every member; every member's result, by name."""


async def start_round(hw: GridHardware, team: GridTeam) -> int:
    """Agree with the team on the world round at which every member starts (one ``and``
    step): a little after the latest round any member has seen."""

    async def now() -> int:
        return hw.clock.now()

    rounds = await team.distributed_and(now)
    return max(int(r) for r in rounds.values()) + START_LEAD


def member_index(robot: Robot[GridHardware], team: GridTeam) -> int:
    """This robot's index in the team (members in name order, as the world applies actions)."""
    return sorted(team.members).index(robot.id)


def perception(hw: GridHardware) -> Perception:
    """The marking agents' perception: the cell here and the free 4-neighbours."""
    h = hw.senses.here()
    near = tuple(Neighbour(n.direction, n.value, n.colour, n.resource, n.base) for n in _free(hw))
    return Perception(h.value, h.colour, h.resource, h.base, near)


def ant_perception(hw: GridHardware) -> AntPerception:
    """The ants' perception: pheromone here and around, resources, the nest compass."""
    h = hw.senses.here()
    near = tuple(AntNeighbour(n.direction, n.pheromone, n.resource, n.base) for n in _free(hw))
    return AntPerception(h.pheromone, h.resource, h.base, near, hw.senses.compass())


def _free(hw: GridHardware) -> list[Near]:
    """The readings of the free 4-neighbours (the agents move in four directions only)."""
    return [n for n in hw.senses.around() if n.state != OBSTACLE and n.direction < 4]


def act(hw: GridHardware, a: Action) -> None:
    """Hand a behaviour's action to the hardware for this round."""
    hw.floor.write(a.value, a.colour)
    if a.load:
        hw.gripper.pick(a.load)
    if a.unload:
        hw.gripper.drop()
    if a.drop:
        hw.floor.scent(a.drop)
    hw.drive.move(a.move)


async def foraging(
    robot: Robot[GridHardware],
    team: GridTeam,
    method: str = "cmarking",
    seed: int | list[int] | None = None,
    q_max: int = 100,
    max_rounds: int = 0,
) -> dict[str, Any]:
    """Forage with ``method`` until the world says the resources are exhausted.

    Agent ``i`` (the ``i``-th member in name order) draws from the ``i``-th generator spawned
    from ``SeedSequence(seed)`` (default: the run's seed, ``team.seed``), as the in-process
    runner's agents do; on a world with sequential turns the run then repeats the in-process
    one. Returns this robot's rounds, units it delivered and cells it moved.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose from {', '.join(METHODS)}")
    hw = robot.hw
    seed = team.seed if seed is None else seed
    rng = np.random.default_rng(np.random.SeedSequence(seed)).spawn(len(team.members))[
        member_index(robot, team)
    ]
    decide = _decider(method, rng, q_max, hw)
    rounds = delivered = moves = 0
    async with hw.clock.owned(at=await start_round(hw, team)):
        while not hw.clock.ended() and not (max_rounds and rounds >= max_rounds):
            a = decide()
            act(hw, a)
            carried = hw.gripper.carried()
            await hw.clock.tick()
            if a.unload and hw.gripper.carried() == 0:
                delivered += carried
            moves += hw.drive.moved()
            rounds += 1
    return {"rounds": rounds, "delivered": delivered, "moves": moves, "finished": hw.clock.ended()}


def _decider(
    method: str, rng: np.random.Generator, q_max: int, hw: GridHardware
) -> Callable[[], Action]:
    """This round's action of a ``method`` agent, from what it perceives on ``hw`` now."""
    if method == "ants":
        ant = AntAgent(rng, q_max)
        return lambda: ant.step(ant_perception(hw))
    marker = CMarkingAgent(rng, q_max) if method == "cmarking" else ForagingMarkingAgent(rng, q_max)
    return lambda: marker.step(perception(hw))
