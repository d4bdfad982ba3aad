"""The seeded arena the foraging team tests run on: random obstacles, the base at the centre,
resource piles placed off the base."""

from __future__ import annotations

from sim_hw.grid import Cell, Grid, GridWorld, place_resources, random_obstacles


def seeded_arena(
    side: int, density: float, seed: int, piles: tuple[int, int, int], n_agents: int
) -> tuple[Grid, Cell, GridWorld]:
    """A ``side`` × ``side`` grid of obstacles (``density``, ``seed``) with the base at its centre
    kept free, ``piles`` = (count, quantity each, seed) of resources off the base, and the world
    on it for ``n_agents`` agents. Returns the grid, the base and the world."""
    base = (side // 2, side // 2)
    grid = random_obstacles(side, side, density, seed, keep_free=(base,))
    count, quantity, pile_seed = piles
    res = place_resources(grid, count, quantity, pile_seed, exclude=(base,))
    return grid, base, GridWorld(grid, base, res, n_agents)
