"""The batched drive (``_drive.BatchDrive``) moves the world as a robot at a time does, bit for
bit: the same poses of every robot and box after every tick."""

from __future__ import annotations

import numpy as np
import pytest

from sim_hw.continuous import _drive

from .test_sonar_batch import _scene


@pytest.mark.parametrize("seed", [1, 2])
def test_the_batched_drive_moves_the_world_as_a_robot_at_a_time_does(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    worlds = {}
    for batch_from in (1, 10**9):  # every tick batched, then never
        monkeypatch.setattr(_drive, "BATCH_FROM", batch_from)
        world = _scene(seed, 0.0)
        rng = np.random.default_rng(seed)
        snapshots = []
        for tick in range(30):
            for rid in sorted(world.robots):
                world.set_command(rid, {"v": float(rng.uniform(-0.5, 0.5)),
                                        "w": float(rng.uniform(-3.0, 3.0))})  # fmt: skip
            if tick == 10:
                world.remove_robot("r05")  # the space's bodies change between ticks
            world.step()
            snapshots.append(world.snapshot())
        worlds[batch_from] = snapshots
    batched, one_at_a_time = worlds[1], worlds[10**9]
    assert batched == one_at_a_time
    first, last = batched[0]["robots"], batched[-1]["robots"]
    assert sum(first[r][:3] != last[r][:3] for r in last) == len(last)  # every robot moved
