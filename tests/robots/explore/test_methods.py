"""Every method explores every reachable cell; runs are seeded; relays are counted."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.maze import run_trial
from robots.explore import METHODS
from sim_hw.grid import generate_maze


@pytest.mark.parametrize("method", list(METHODS))
@pytest.mark.parametrize("p", [0.85, 0.15])
def test_every_method_explores_every_reachable_cell(method: str, p: float) -> None:
    for k in range(2):
        maze = generate_maze(16, p, np.random.default_rng(100 + k), n_starts=4)
        res = run_trial(maze, 1 + 2 * k, method, np.random.SeedSequence(k))
        inner = (maze.shape[0] - 2) * (maze.shape[1] - 2)
        assert res["complete"], (method, p, k)
        assert res["explored"] == res["observable"] == inner
        assert res["quality"] == 1.0


@pytest.mark.parametrize("method", ["cu-lvp", "nf", "cu-bso", "hedac"])
def test_same_seed_same_run(method: str) -> None:
    maze = generate_maze(20, 0.85, np.random.default_rng(9), n_starts=6)
    a = run_trial(maze, 6, method, np.random.SeedSequence(42))
    b = run_trial(maze, 6, method, np.random.SeedSequence(42))
    for key in ("step_ms", "time_s"):
        a.pop(key), b.pop(key)
    assert a == b


@pytest.mark.parametrize(
    ("run", "method"),
    [(67, "cu-lvp"), (42, "cu-lvp"), (61, "nf"), (63, "cu-mnm"), (66, "cu-jgr"), (67, "cu-bso")],
)
def test_two_agents_meeting_in_corridors_do_not_livelock(run: int, method: str) -> None:
    # Seeded mazes where two agents once met head-on and waited for, or danced around, each
    # other until the round cap (experiment seed 2026, p = 0.85, 2 agents).
    maze = generate_maze(
        30, 0.85, np.random.default_rng(np.random.SeedSequence([2026, 30, 850, run])), n_starts=20
    )
    seed = np.random.SeedSequence([2026, 30, 850, run, 2, list(METHODS).index(method)])
    res = run_trial(maze, 2, method, seed, max_rounds=1500)
    assert res["complete"]


def test_hedac_agents_caught_in_a_two_cell_cycle_break_out() -> None:
    # Experiment seed 2026, p = 0.85, maze 6, 15 agents: with relays all fifteen HEDAC agents
    # once went back and forth between two cells each, with 19 cells left, until the cap.
    maze = generate_maze(
        30, 0.85, np.random.default_rng(np.random.SeedSequence([2026, 30, 850, 6])), n_starts=20
    )
    seed = np.random.SeedSequence([2026, 30, 850, 6, 15, list(METHODS).index("hedac")])
    res = run_trial(maze, 15, "hedac", seed, max_rounds=400, exchanges=3)
    assert res["complete"]


def test_relays_are_counted_and_can_be_turned_off() -> None:
    maze = generate_maze(30, 0.85, np.random.default_rng(3), n_starts=8)
    # (without the news passed on: what changed since an agent's last message is spread over
    # a round's exchanges, so with it three exchanges can cost fewer bytes a round than one)
    one = run_trial(maze, 8, "cu-lvp", np.random.SeedSequence(1), exchanges=1, news="off")
    three = run_trial(maze, 8, "cu-lvp", np.random.SeedSequence(1), exchanges=3, news="off")
    assert one["complete"] and three["complete"]
    # the relays' bytes are sent on top of the round's broadcasts
    assert three["comm_sent_kB"] / three["rounds"] > one["comm_sent_kB"] / one["rounds"]
