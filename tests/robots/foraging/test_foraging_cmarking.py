"""C-marking agents (Simonin et al., Algorithm 4): trails are created, climbed and removed, with
one trail colour or one colour per trail."""

from __future__ import annotations

import numpy as np
import pytest

from robots.foraging import (
    NO_COLOUR,
    TRAIL,
    CMarkingAgent,
    Neighbour,
    Perception,
    Task,
    ending,
)
from sim_hw.grid import Grid, GridWorld
from tests.robots.foraging._arena import seeded_arena
from tests.robots.foraging.test_foraging_marking import lemma_4_1_holds


def agent(seed: int = 0, **kw: object) -> CMarkingAgent:
    return CMarkingAgent(np.random.default_rng(seed), **kw)  # type: ignore[arg-type]


def perception(
    value: int, colour: int, resource: int, *nbrs: tuple[int, int, int, int]
) -> Perception:
    """Neighbours as (direction, value, colour, resource)."""
    return Perception(
        value, colour, resource, False, tuple(Neighbour(d, v, c, r, False) for d, v, c, r in nbrs)
    )


def test_loading_chooses_the_return_task() -> None:
    a = agent()
    act = a.step(perception(6, NO_COLOUR, 500, (0, 5, 0, 0), (1, 7, 0, 0)))
    assert (act.load, act.colour, act.move, a.task) == (100, TRAIL, 0, Task.COLOUR)
    b = agent()
    act = b.step(perception(6, TRAIL, 500, (0, 5, TRAIL, 0), (1, 7, 0, 0)))
    assert (act.load, act.colour, b.task) == (100, None, Task.RETURN)  # a trail is there
    c = agent()
    act = c.step(perception(6, TRAIL, 100, (0, 5, TRAIL, 0), (1, 7, 0, 0)))
    assert (act.load, act.colour, act.move, c.task) == (100, NO_COLOUR, 0, Task.REMOVE)


def test_colour_on_move_leaves_the_source_cell_alone() -> None:
    a = agent(colour_source=False)
    act = a.step(perception(6, NO_COLOUR, 500, (0, 5, 0, 0), (1, 7, 0, 0)))
    assert (act.load, act.colour, a.task) == (100, None, Task.COLOUR)
    assert a.step(perception(5, NO_COLOUR, 0, (0, 4, 0, 0))).colour == TRAIL  # the next cell


def test_search_moves_to_resource_then_climbs_the_highest_trail_cell() -> None:
    a = agent()
    assert a.step(perception(4, 0, 0, (0, 5, TRAIL, 0), (1, 3, 0, 50))).move == 1
    act = a.step(perception(4, 0, 0, (0, 5, TRAIL, 0), (1, 3, TRAIL, 0), (2, 6, TRAIL, 0)))
    assert act.move == 2
    assert a.came_from == 0  # the opposite of south
    act = a.step(perception(6, TRAIL, 0, (0, 5, TRAIL, 0), (1, 7, TRAIL, 0)))
    assert act.move == 1 and a.task == Task.SEARCH


def test_dead_end_of_a_trail_is_removed() -> None:
    a = agent()
    a.came_from = 2
    act = a.step(perception(9, TRAIL, 0, (2, 8, TRAIL, 0), (1, 10, 0, 0)))
    assert (a.task, act.colour, act.move) == (Task.REMOVE, NO_COLOUR, 2)
    literal = agent(remove_dead_ends=False)
    literal.came_from = 2
    literal.step(perception(9, TRAIL, 0, (2, 8, TRAIL, 0), (1, 10, 0, 0)))
    assert literal.task == Task.SEARCH


def test_previous_position_is_not_climbed_back_from_the_base() -> None:
    a = agent()
    a.task, a.came_from = Task.RETURN, 1  # came down the trail from the east
    base = Perception(
        0, 0, 0, True, (Neighbour(1, 1, TRAIL, 0, False), Neighbour(2, 1, 0, 0, False))
    )
    act = a.step(base)
    assert act.unload and a.task == Task.SEARCH and act.move == 2  # explores instead
    b = agent(forget_at_base=True)
    b.task, b.came_from = Task.RETURN, 1
    assert b.step(base).move == 1


def trail_cells(world: GridWorld) -> set[tuple[int, int]]:
    cols = world.colours_array()
    return {(int(r), int(c)) for r, c in zip(*np.nonzero(cols == TRAIL), strict=True)}


def test_trail_created_climbed_and_removed_when_source_exhausted() -> None:
    grid = Grid(np.zeros((9, 9), dtype=bool))
    base, source = (4, 4), (0, 1)
    world = GridWorld(grid, base, {source: 300}, 1)
    a = agent(3, forget_at_base=True)  # straight back up its own trail, to count the moves
    # First trip: explore, find the source, colour the way back.
    while world.carried[0] == 0:
        world.step([a])
    loaded = world.iteration
    while world.delivered == 0:
        world.step([a])
    trail = trail_cells(world)
    assert source in trail and base not in trail
    assert len(trail) == world.iteration - loaded  # one cell coloured per step home
    assert any(n in trail for n in grid.neighbours(base))
    assert all(any(n in trail for n in grid.neighbours(c)) for c in trail)  # connected
    # From the base the trail is climbed straight to the source: the unloading step already
    # moved onto the first trail cell, then one move per trail cell left and one loading step.
    start = world.iteration
    while world.carried[0] == 0:
        world.step([a])
    assert world.iteration - start == len(trail)
    assert a.task == Task.RETURN  # the source is on a trail: plain descent home
    while world.delivered < 300:
        world.step([a])
    assert world.exhausted
    assert trail_cells(world) == set()  # RETURN & REMOVE TRAIL erased it


def test_team_forages_with_trails_and_keeps_lemma_4_1() -> None:
    grid, base, world = seeded_arena(31, 0.30, 8, piles=(8, 500, 9), n_agents=10)
    agents = [CMarkingAgent(r) for r in np.random.default_rng(10).spawn(10)]
    seen_trail = False
    while not world.exhausted and world.iteration < 50_000:
        world.step(agents)
        seen_trail = seen_trail or bool(trail_cells(world))
        assert lemma_4_1_holds(world.marks_array(), grid, base)  # trails leave the field intact
    assert world.exhausted and seen_trail


# -- one colour per trail ---------------------------------------------------------------------
A_BIT, B_BIT = 1, 2  # trail colours: the first trail of agents 0 and 1 of a team of 2


def test_ending_is_the_trails_carried_by_at_most_one_neighbour() -> None:
    nbrs = tuple(Neighbour(d, 3, c, 0, False) for d, c in enumerate((A_BIT | B_BIT, B_BIT, 0)))
    assert ending(A_BIT | B_BIT, nbrs) == A_BIT  # B passes through, A ends here
    assert ending(NO_COLOUR, nbrs) == NO_COLOUR


def test_per_trail_loading_creates_a_trail_of_its_own_beside_a_passing_one() -> None:
    a = agent(0, trail_colours="per-trail", ident=1, team=2)
    # a source crossed by trail A (carried by two neighbours): not the end of any trail
    act = a.step(perception(6, A_BIT, 500, (0, 5, A_BIT, 0), (2, 7, A_BIT, 0)))
    assert (a.task, act.colour) == (Task.COLOUR, A_BIT | B_BIT)  # its own bit added
    assert a.step(perception(5, A_BIT, 0, (0, 4, A_BIT, 0))).colour == A_BIT | B_BIT
    second = agent(1, trail_colours="per-trail", ident=0, team=2)
    act = second.step(perception(6, A_BIT | B_BIT, 500, (0, 5, A_BIT | B_BIT, 0),
                                 (2, 7, A_BIT, 0)))  # fmt: skip
    assert (second.task, act.colour) == (Task.RETURN, None)  # trail B ends here: descend
    assert agent(2, trail_colours="per-trail", ident=1, team=2)._new_colour() == B_BIT
    with pytest.raises(ValueError, match="colour_source"):
        agent(trail_colours="per-trail", colour_source=False)
    with pytest.raises(ValueError, match="ident"):
        agent(trail_colours="per-trail", ident=2, team=2)


def merged_trails(colour_a: int, colour_b: int) -> tuple[GridWorld, list[tuple[int, int]]]:
    """Two trails that merge two cells before the base; the remover stands on source A.

    ::

        . . B      row 0: B at (0, 4), its trail (0, 3), (0, 2), (1, 2), (2, 2), (2, 1)
        # . # #    row 1
        . . . A    row 2: base (2, 0), A at (2, 4), its trail (2, 3), (2, 2), (2, 1)
    """
    grid = Grid(np.array([[1, 1, 0, 0, 0], [1, 1, 0, 1, 1], [0, 0, 0, 0, 0]], dtype=bool))
    base, a_src, b_src = (2, 0), (2, 4), (0, 4)
    world = GridWorld(grid, base, {a_src: 100, b_src: 1000}, starts=[a_src])
    world.marks = [int(v) if v >= 0 else -1 for v in grid.distances(base).ravel()]
    trail_b = [b_src, (0, 3), (0, 2), (1, 2), (2, 2), (2, 1)]
    for c in trail_b:
        world.colours[grid.index(c)] |= colour_b
    for c in [a_src, (2, 3), (2, 2), (2, 1)]:
        world.colours[grid.index(c)] |= colour_a
    return world, trail_b


def test_per_trail_removal_leaves_a_merged_trail_whole() -> None:
    world, trail_b = merged_trails(A_BIT, B_BIT)
    remover = agent(0, trail_colours="per-trail", ident=0, team=2)
    world.step([remover])  # loads the last 100 units: RETURN & REMOVE TRAIL of A only
    assert remover.task == Task.REMOVE and remover.trail == A_BIT
    while world.agent_cell(0) != (2, 0):
        world.step([remover])
    colours = {world.grid.cell(i): c for i, c in enumerate(world.colours) if c}
    assert colours == {c: B_BIT for c in trail_b}  # A erased, B whole from its source down


def test_single_colour_removal_cuts_a_merged_trail() -> None:
    world, trail_b = merged_trails(TRAIL, TRAIL)
    remover = agent(0)
    while world.agent_cell(0) != (2, 0) or world.iteration == 0:
        world.step([remover])
    left = {world.grid.cell(i) for i, c in enumerate(world.colours) if c}
    assert left == set(trail_b[:4])  # B's trail now ends two cells short of the base


def test_per_trail_team_forages_and_keeps_lemma_4_1() -> None:
    grid, base, world = seeded_arena(31, 0.05, 8, piles=(8, 500, 9), n_agents=10)
    agents = [
        CMarkingAgent(r, trail_colours="per-trail", ident=i, team=10)
        for i, r in enumerate(np.random.default_rng(10).spawn(10))
    ]
    bits = 0
    while not world.exhausted and world.iteration < 50_000:
        world.step(agents)
        for c in world.colours:
            bits |= c
        assert lemma_4_1_holds(world.marks_array(), grid, base)
    assert world.exhausted and bin(bits).count("1") >= 2  # several trails, each its own colour


def test_per_trail_dead_end_erases_a_peak_but_not_a_trail_going_on() -> None:
    a = agent(trail_colours="per-trail", ident=0, team=2)
    a.came_from = 2  # climbed from the south onto a peak: trail A falls on both sides
    act = a.step(perception(9, A_BIT | B_BIT, 0, (2, 8, A_BIT, 0), (1, 7, A_BIT, 0),
                            (3, 8, B_BIT, 0), (0, 10, B_BIT, 0)))  # fmt: skip
    assert a.task == Task.SEARCH and act.move == 0  # B goes on up: climbed, nothing erased
    b = agent(trail_colours="per-trail", ident=0, team=2)
    b.came_from = 2
    act = b.step(perception(9, A_BIT, 0, (2, 8, A_BIT, 0), (1, 7, A_BIT, 0)))
    assert (b.task, b.trail, act.colour, act.move) == (Task.REMOVE, A_BIT, NO_COLOUR, 1)


def test_per_trail_climber_keeps_to_the_trails_of_its_cell() -> None:
    cell = (4, A_BIT, 0, (0, 5, A_BIT, 0), (1, 8, B_BIT, 0))
    assert agent(trail_colours="per-trail").step(perception(*cell)).move == 0  # stays on A
    assert agent().step(perception(4, TRAIL, 0, (0, 5, TRAIL, 0), (1, 8, TRAIL, 0))).move == 1
    off = agent(trail_colours="per-trail").step(perception(4, 0, 0, *cell[3:]))
    assert off.move == 1  # off the trails: the highest coloured cell, whichever trail
