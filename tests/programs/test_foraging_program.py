"""The foraging program on the grid HAL's fakes (``robots.testing``): what it perceives, what it
hands the hardware, and its loop from the agreed start to the observer's end. No world, no
network: the program's own logic (its runs on a world are in test_grid_inprocess.py and
test_foraging_processes.py)."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from programs.foraging import START_LEAD, GridTeam, act, ant_perception, foraging, perception
from robots import Robot
from robots.foraging import Action, AntNeighbour, Neighbour
from robots.grid_hal import FREE, OBSTACLE, OCCUPIED, Here, Near
from robots.testing import (
    FakeGridDrive,
    FakeGridFloor,
    FakeGridGripper,
    FakeGridSenses,
    FakeRoundClock,
    fake_grid_hardware,
)

NORTH, EAST, SOUTH, WEST, NORTH_EAST = range(5)

AROUND = (
    Near(NORTH, FREE, 3, 1, 0, False, 0.5),
    Near(EAST, OBSTACLE, 0, 0, 0, False),
    Near(SOUTH, OCCUPIED, -1, 0, 20, True, 0.25),  # another robot stands there: still a cell
    Near(WEST, FREE, -1, 0, 0, False),
    Near(NORTH_EAST, FREE, 9, 9, 9, False),  # a diagonal: the agents move in four directions
)


class _Alone:
    """A team of one (a :class:`GridTeam`): its ``and`` step is its own value."""

    members = ("a",)
    seed = 7

    async def distributed_and(self, operation: Callable[[], Awaitable[Any]]) -> dict[str, Any]:
        return {"a": await operation()}


def test_the_agents_perceive_the_free_four_neighbours() -> None:
    senses = FakeGridSenses(cell=Here(2, 1, 40, False, 0.75), near=AROUND, heading=(0.0, -1.0))
    hw = fake_grid_hardware(senses=senses)
    assert perception(hw) == (
        2,
        1,
        40,
        False,
        (
            Neighbour(NORTH, 3, 1, 0, False),
            Neighbour(SOUTH, -1, 0, 20, True),
            Neighbour(WEST, -1, 0, 0, False),
        ),
    )
    ants = ant_perception(hw)
    assert ants.pheromone == 0.75 and ants.home == (0.0, -1.0)
    assert [n.direction for n in ants.neighbours] == [NORTH, SOUTH, WEST]
    assert ants.neighbours[0] == AntNeighbour(NORTH, 0.5, 0, False)


async def test_an_action_goes_to_the_hardware_at_the_round_s_end() -> None:
    floor, gripper = FakeGridFloor(), FakeGridGripper(lying=30)
    hw = fake_grid_hardware(floor=floor, gripper=gripper)
    act(hw, Action(move=EAST, value=5, colour=2, load=10, drop=1.5))
    assert hw.floor.read() == (5, 2) and hw.gripper.carried() == 0  # asked, not done yet
    await hw.clock.tick()
    assert (floor.value, floor.colour, floor.pheromone) == (5, 2, 1.5)
    assert hw.gripper.carried() == 10 and hw.odometry.pose() == (0.0, 1.0, 0.0)
    act(hw, Action(move=None, unload=True))
    await hw.clock.tick()
    assert gripper.dropped == 10 and not hw.drive.moved()


async def test_the_program_starts_at_the_agreed_round_and_ends_with_the_observer() -> None:
    clock, drive = FakeRoundClock(start=3, end=3 + START_LEAD + 4), FakeGridDrive()
    hw = fake_grid_hardware(clock=clock, drive=drive)
    team: GridTeam = _Alone()
    out = await foraging(Robot("a", hw), team, method="marking")
    # the team agreed on round 3 + START_LEAD; four rounds of foraging from there
    assert out == {"rounds": 4, "delivered": 0, "moves": 4, "finished": True}
    assert len(drive.commands) == 4 and None not in drive.commands  # it moved every round


async def test_the_program_stops_after_max_rounds() -> None:
    hw = fake_grid_hardware()
    out = await foraging(Robot("a", hw), _Alone(), method="ants", seed=1, max_rounds=3)
    assert out["rounds"] == 3 and not out["finished"] and hw.clock.now() == START_LEAD + 3
