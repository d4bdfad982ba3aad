"""A grid team's ``distributed_or`` in simulated time over processes: a grid world process and
two grid robot processes, each run's clock the robot process's ``HostClock`` over its grid
clock (which holds a member past the earliest finish, and lets go once decided)."""

from __future__ import annotations

import asyncio
from pathlib import Path

import numpy as np
import pytest

from mover import Node, launch
from tests.helpers.procs import cluster
from tests.programs._grid import WORLD, start_world, write_grid

pytestmark = pytest.mark.processes


async def test_a_grid_team_decides_an_or_in_rounds_over_processes(tmp_path: Path) -> None:
    path = write_grid(tmp_path / "open.json", np.zeros((5, 5), dtype=bool), (2, 2), {})
    names = ["a", "b"]
    async with cluster() as c, Node("launcher", c.team, kind="tool", config=c.seed) as node:
        await start_world(c, path, "--expect", "2")
        await asyncio.gather(
            *(c.start("tests.programs.grid_or_robot", n, timeout=40.0) for n in names)
        )
        await node.membership.wait_for([WORLD, *names], timeout=20)
        ends = {"a": 6, "b": 3}
        outcomes = await asyncio.wait_for(
            launch(node, "or_rounds", names, {"ends": ends}, run="or-in-rounds"), 60
        )
        assert {n: o.get("result") for n, o in outcomes.items()} == {"a": 3, "b": 3}, outcomes
