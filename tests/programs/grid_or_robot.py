"""A grid robot process hosting one test program, ``or_rounds``, for the grid OR test.

``python -m tests.programs.grid_or_robot NAME``: the robot process of ``mover robot
--hardware grid`` (team and zenoh settings from the MOVER_* environment). Prints ``READY``
once its hardware is up.
"""

from __future__ import annotations

from mover import RunTeam
from robots import Robot
from robots.grid_hal import GridHardware
from tests.helpers.robot_main import run_test_robot


async def or_rounds(robot: Robot[GridHardware], team: RunTeam, ends: dict[str, int]) -> int:
    """A ``distributed_or`` in which each member hands in actions until its round in ``ends``;
    returns the winner's round."""
    hw = robot.hw

    async def walk() -> int:
        while hw.clock.now() < ends[robot.id]:
            await hw.clock.tick()
        return hw.clock.now()

    outcome = await team.distributed_or(walk)
    return int(outcome.result)


if __name__ == "__main__":
    run_test_robot(
        {"or_rounds": or_rounds},
        hardware="grid",
        options={"world": "gridworld", "idle_period": 0.0},
    )
