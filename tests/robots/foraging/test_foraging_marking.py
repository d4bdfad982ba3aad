"""Marking agents (Simonin et al., Algorithms 2 and 3): Theorem 3.1, Lemma 4.1, descent."""

from __future__ import annotations

import numpy as np
import pytest

import robots.foraging as foraging
from robots.foraging import (
    UNMARKED,
    ForagingMarkingAgent,
    MarkingAgent,
    Neighbour,
    Perception,
    update_value,
)
from robots.foraging._dice import Dice
from robots.foraging._marking import descend, explore
from sim_hw.grid import Grid, GridWorld, maze, random_obstacles
from tests.robots.foraging._arena import seeded_arena


def p(value: int, *nbrs: tuple[int, int]) -> Perception:
    """A perception with neighbours given as (direction, value)."""
    return Perception(value, 0, 0, False, tuple(Neighbour(d, v, 0, 0, False) for d, v in nbrs))


def test_public_face() -> None:
    for name in foraging.__all__:
        assert getattr(foraging, name) is not None


def test_update_value() -> None:
    assert update_value(p(UNMARKED, (0, 4), (1, UNMARKED), (2, 7))) == 5
    assert update_value(p(3, (0, 4), (1, 9))) == 3  # only ever lowered
    assert update_value(p(9, (0, 4))) == 5
    assert update_value(p(UNMARKED, (0, UNMARKED))) == UNMARKED


def test_explore_prefers_unmarked_and_descend_takes_least() -> None:
    dice = Dice(np.random.default_rng(0))
    nbrs = p(3, (0, 2), (1, UNMARKED), (2, 4)).neighbours
    assert {explore(nbrs, dice) for _ in range(50)} == {1}
    assert {descend(nbrs, dice) for _ in range(50)} == {0}
    ties = p(3, (0, 2), (1, 2), (2, 4)).neighbours
    assert {descend(ties, dice) for _ in range(100)} == {0, 1}


def lemma_4_1_holds(marks: np.ndarray, grid: Grid, base: tuple[int, int]) -> bool:
    """Every marked cell but the base has a neighbour with a lower value (vectorised)."""
    big = np.iinfo(np.int64).max
    m = np.pad(np.where(marks >= 0, marks, big), 1, constant_values=big)
    lowest = np.minimum.reduce([m[:-2, 1:-1], m[2:, 1:-1], m[1:-1, :-2], m[1:-1, 2:]])
    ok = (marks < 0) | (lowest < marks)
    ok[base] = True
    return bool(ok.all())


def descent_reaches_base(marks: np.ndarray, grid: Grid, base: tuple[int, int]) -> bool:
    """From every marked cell, always stepping to a least-valued neighbour ends at the base."""
    for r, c in zip(*np.nonzero(marks >= 0), strict=True):
        cell = (int(r), int(c))
        for _ in range(marks.size):
            if cell == base:
                break
            cell = min((n for n in grid.neighbours(cell) if marks[n] >= 0), key=lambda n: marks[n])
        if cell != base:
            return False
    return True


def build(grid: Grid, base: tuple[int, int], n: int, seed: int, lemma_every: int) -> GridWorld:
    world = GridWorld(grid, base, None, n)
    agents = [MarkingAgent(r) for r in np.random.default_rng(seed).spawn(n)]
    target = grid.distances(base)
    for it in range(200_000):
        world.step(agents)
        if it % lemma_every == 0:
            marks = world.marks_array()
            assert lemma_4_1_holds(marks, grid, base), f"Lemma 4.1 broken at iteration {it}"
            if it % (lemma_every * 200) == 0:
                assert descent_reaches_base(marks, grid, base)
        if np.array_equal(world.marks_array(), target):
            return world
    raise AssertionError("the field did not converge")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_field_converges_to_bfs_on_random_obstacles(seed: int) -> None:
    base = (12, 12)
    grid = random_obstacles(25, 25, 0.30, seed, keep_free=(base,))
    world = build(grid, base, 8, seed, lemma_every=1)  # Lemma 4.1 checked at every step
    assert np.array_equal(world.marks_array(), grid.distances(base))  # Theorem 3.1
    assert descent_reaches_base(world.marks_array(), grid, base)


def test_field_converges_in_a_maze_with_one_agent() -> None:
    grid = maze(15, 15, seed=3)
    build(grid, (7, 7), 1, 5, lemma_every=7)


def test_seeded_agents_repeat_exactly() -> None:
    grid = random_obstacles(15, 15, 0.2, 1, keep_free=((7, 7),))

    def trajectory(seed: int) -> list[tuple[int, ...]]:
        world = GridWorld(grid, (7, 7), None, 3)
        agents = [MarkingAgent(r) for r in np.random.default_rng(seed).spawn(3)]
        out = []
        for _ in range(50):
            world.step(agents)
            out.append(tuple(world.positions))
        return out

    assert trajectory(9) == trajectory(9)
    assert trajectory(9) != trajectory(10)


def test_foraging_marking_agents_bring_everything_home() -> None:
    grid, base, world = seeded_arena(21, 0.2, 4, piles=(3, 300, 5), n_agents=6)
    agents = [ForagingMarkingAgent(r) for r in np.random.default_rng(6).spawn(6)]
    while not world.all_delivered and world.iteration < 50_000:
        world.step(agents)
        if world.iteration % 25 == 0:
            assert lemma_4_1_holds(world.marks_array(), grid, base)
    assert world.all_delivered and world.delivered == 900


def test_lemma_check_detects_a_local_minimum() -> None:
    grid = Grid(np.zeros((1, 4), dtype=bool))
    assert lemma_4_1_holds(np.array([[0, 1, 2, 3]]), grid, (0, 0))
    assert not lemma_4_1_holds(np.array([[0, 1, 3, 3]]), grid, (0, 0))  # a flat spot
