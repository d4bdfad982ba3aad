"""The discrete grid world for the grid-based papers (Simonin et al. and others).

Free/obstacle cells with 4-neighbour moves (agents may share a cell), a digital floor of integer
values and colours, resources with quantities, a base, an optional pheromone layer, view rays
blocked by obstacles and range queries; grid files (text or JSON) and seeded generators; the
Linardakis maze (generator, files, the star view); the :class:`GridServer` (a grid world and its
lock-step door, ``server.door``) and its robot-side backend (:func:`in_process`, :func:`connect`).

Example::

    grid = random_obstacles(40, 40, 0.30, seed=1, keep_free=((20, 20),))
    world = GridWorld(grid, (20, 20), place_resources(grid, 20, 1000, seed=2), n_agents=10)
    world.step(behaviours)  # one iteration: every agent perceives, acts, moves
"""

from sim_hw._lockstep import RobotDropped
from sim_hw.grid._errors import GridFileError
from sim_hw.grid._generate import double_corridor, maze, place_resources, random_obstacles
from sim_hw.grid._grid import OFFSETS4, OFFSETS8, Cell, Grid
from sim_hw.grid._hardware import GridRobot, connect, in_process
from sim_hw.grid._io import Layout, load_grid, load_layout, parse_json, parse_text
from sim_hw.grid._maze import (
    Maze,
    MazeFileError,
    broadcast_range,
    generate_maze,
    load_maze,
    maze_world,
    observable,
    random_starts,
    save_maze,
    star_view,
)
from sim_hw.grid._pheromone import PheromoneField
from sim_hw.grid._render import render_text
from sim_hw.grid._sensing import disc_view, line_of_sight, ray_cells, within_range
from sim_hw.grid._server import GridServer, GridStepper, serve_grid
from sim_hw.grid._world import Behaviour, GridWorld

__all__ = [
    "OFFSETS4",
    "OFFSETS8",
    "Behaviour",
    "Cell",
    "Grid",
    "GridFileError",
    "GridRobot",
    "GridServer",
    "GridStepper",
    "GridWorld",
    "Layout",
    "Maze",
    "MazeFileError",
    "PheromoneField",
    "RobotDropped",
    "broadcast_range",
    "connect",
    "disc_view",
    "double_corridor",
    "generate_maze",
    "in_process",
    "line_of_sight",
    "load_grid",
    "load_layout",
    "load_maze",
    "maze",
    "maze_world",
    "observable",
    "parse_json",
    "parse_text",
    "place_resources",
    "random_obstacles",
    "random_starts",
    "ray_cells",
    "render_text",
    "save_maze",
    "serve_grid",
    "star_view",
    "within_range",
]
