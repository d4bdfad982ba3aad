"""The grid, its generators, the world's step API, pheromone dynamics and sensing."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest

import sim_hw.grid as grid_pkg
from robots.foraging import EAST, NORTH, WEST, Action, MarkingAgent
from sim_hw.grid import (
    Grid,
    GridWorld,
    PheromoneField,
    disc_view,
    double_corridor,
    line_of_sight,
    maze,
    parse_text,
    place_resources,
    random_obstacles,
    within_range,
)


def test_public_face() -> None:
    for name in grid_pkg.__all__:
        assert getattr(grid_pkg, name) is not None
    assert sorted(grid_pkg.__all__) == sorted(set(grid_pkg.__all__))


def test_distances_is_algorithm1() -> None:
    g = parse_text("....\n.##.\n....\n").grid
    d = g.distances((0, 0))
    assert d.tolist() == [[0, 1, 2, 3], [1, -1, -1, 4], [2, 3, 4, 5]]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_obstacles_seeded_connected(seed: int) -> None:
    a = random_obstacles(40, 40, 0.30, seed, keep_free=((20, 20),))
    b = random_obstacles(40, 40, 0.30, seed, keep_free=((20, 20),))
    assert a == b
    assert a != random_obstacles(40, 40, 0.30, seed + 10, keep_free=((20, 20),))
    assert a.is_free((20, 20))
    assert np.array_equal(a.reachable((20, 20)), ~a.obstacles)  # every free cell reachable
    assert 0.30 <= a.density < 0.40


def test_random_obstacles_unconnected_density_exact() -> None:
    g = random_obstacles(20, 20, 0.25, 3, connected=False)
    assert int(g.obstacles.sum()) == 100


def test_maze_seeded_and_perfect() -> None:
    m = maze(21, 31, seed=4)
    assert m == maze(21, 31, seed=4)
    assert m != maze(21, 31, seed=5)
    free = ~m.obstacles
    assert np.array_equal(m.reachable((1, 1)), free)
    edges = int((free[1:, :] & free[:-1, :]).sum() + (free[:, 1:] & free[:, :-1]).sum())
    assert edges == int(free.sum()) - 1  # a tree: exactly one path between two cells


def test_double_corridor() -> None:
    g = double_corridor(7)
    assert g.to_text() == "#########\n#.......#\n#.#####.#\n#.......#\n#########\n"


def test_place_resources_seeded() -> None:
    g = random_obstacles(30, 30, 0.3, 1, keep_free=((15, 15),))
    a = place_resources(g, 20, 1000, 7, exclude=((15, 15),), reachable_from=(15, 15))
    assert a == place_resources(g, 20, 1000, 7, exclude=((15, 15),), reachable_from=(15, 15))
    assert len(a) == 20 and (15, 15) not in a
    assert all(g.is_free(c) and q == 1000 for c, q in a.items())


def small_world(n: int = 2) -> GridWorld:
    g = parse_text(".....\n.#...\n.....\n").grid
    return GridWorld(g, (0, 0), {(2, 4): 150}, n)


def test_world_perception_and_moves() -> None:
    w = small_world()
    p = w.perceive(0)
    assert p.at_base and p.value == 0
    assert [n.direction for n in p.neighbours] == [EAST, 2]
    w.apply(0, Action(EAST, value=None))
    w.apply(1, Action(EAST))
    assert w.agent_cell(0) == w.agent_cell(1) == (0, 1)  # agents may share a cell
    with pytest.raises(ValueError, match="obstacle"):
        w.apply(0, Action(2))  # (1, 1) is an obstacle
    with pytest.raises(ValueError, match="obstacle"):
        w.apply(0, Action(NORTH))  # outside the rectangle counts as obstacle


def test_world_load_unload() -> None:
    g = Grid(np.zeros((1, 3), dtype=bool))
    w = GridWorld(g, (0, 0), {(0, 2): 150}, starts=[(0, 2)])
    w.apply(0, Action(WEST, load=100))
    assert w.remaining == 50 and w.carried == [100]
    w.apply(0, Action(WEST, unload=True))  # not at the base yet: nothing delivered
    assert w.delivered == 0 and w.agent_cell(0) == (0, 0)
    w.apply(0, Action(EAST, unload=True))
    assert w.delivered == 100 and w.carried == [0]
    w.apply(0, Action(EAST))
    w.apply(0, Action(None, load=100))  # only what is left
    assert w.remaining == 0 and w.carried == [50] and w.exhausted and not w.all_delivered


def test_world_state_is_msgpack_round_trip() -> None:
    w = small_world(3)
    agents = [MarkingAgent(r) for r in np.random.default_rng(1).spawn(3)]
    for _ in range(5):
        w.step(agents)
    blob = msgpack.packb(w.to_dict())
    w2 = GridWorld.from_dict(msgpack.unpackb(blob))
    assert w2.to_dict() == w.to_dict()


def test_pheromone_diffusion_conserves_and_evaporates() -> None:
    free = ~parse_text("....\n.#..\n....\n").grid.obstacles
    f = PheromoneField(free, diffusion=0.95, evaporation=0.0)
    f.values[0] = 100.0
    for _ in range(10):
        f.update()
    assert f.total() == pytest.approx(100.0)
    assert f.values[5] == 0.0  # the obstacle cell holds nothing
    f.evaporation = 0.005
    f.update()
    assert f.total() == pytest.approx(99.5)


def test_view_rays_and_range() -> None:
    g = parse_text(".....\n..#..\n.....\n").grid
    assert not line_of_sight(g, (1, 0), (1, 4))
    assert line_of_sight(g, (0, 0), (0, 4))
    seen = disc_view(g, (1, 0), 4)
    assert (1, 2) in seen and (1, 3) not in seen
    assert within_range([(0, 0), (0, 3), (2, 0)], 0, 2.0) == [2]
    assert within_range([(0, 0), (0, 3), (2, 0)], 0, 1.5, cell_size=0.5) == [1, 2]
