"""Mazes (section IV-A), maze files, the star sensor (III-A) and the broadcast range (III-B)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mover import ConfigError
from robots.foraging import Action
from robots.grid_hal import direction_of
from sim_hw.grid import (
    Grid,
    GridWorld,
    Maze,
    MazeFileError,
    broadcast_range,
    generate_maze,
    load_maze,
    maze_world,
    save_maze,
    star_view,
)


def _connected(grid: np.ndarray) -> bool:
    free = {tuple(c) for c in np.argwhere(grid == 0)}
    todo = [next(iter(free))]
    seen = {todo[0]}
    while todo:
        r, c = todo.pop()
        for n in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
            if n in free and n not in seen:
                seen.add(n)
                todo.append(n)
    return seen == free


@pytest.mark.parametrize("p", [0.85, 0.15])
def test_generated_maze_is_seeded_walled_and_connected(p: float) -> None:
    a = generate_maze(30, p, np.random.default_rng(7))
    b = generate_maze(30, p, np.random.default_rng(7))
    assert a.grid.shape == (31, 31)
    assert np.array_equal(a.grid, b.grid)
    assert a.starts == b.starts
    g = a.grid
    assert g[0].all()
    assert g[-1].all()
    assert g[:, 0].all()
    assert g[:, -1].all()
    assert _connected(g)
    assert len(set(a.starts)) == 20
    assert all(g[s] == 0 for s in a.starts)


def test_obstacle_probability_sets_density() -> None:
    rng = np.random.default_rng(3)
    dense = np.mean([generate_maze(30, 0.85, rng).grid[1:-1, 1:-1].mean() for _ in range(5)])
    open_ = np.mean([generate_maze(30, 0.15, rng).grid[1:-1, 1:-1].mean() for _ in range(5)])
    assert dense > 0.2 > 0.05 > open_


def test_star_sensor_sees_eight_rays_blocked_by_obstacles() -> None:
    grid = np.array(
        [
            [1, 1, 1, 1, 1, 1, 1],
            [1, 0, 0, 0, 0, 0, 1],
            [1, 0, 1, 0, 0, 0, 1],
            [1, 0, 0, 0, 1, 0, 1],
            [1, 0, 0, 0, 0, 0, 1],
            [1, 0, 0, 0, 0, 0, 1],
            [1, 1, 1, 1, 1, 1, 1],
        ]
    )
    seen = {(r, c): v for r, c, v in star_view(grid, (3, 3), reach=2)}
    expected = {
        (3, 3): 0,
        (2, 3): 0,
        (1, 3): 0,  # up
        (4, 3): 0,
        (5, 3): 0,  # down
        (3, 2): 0,
        (3, 1): 0,  # left
        (3, 4): 1,  # right: stopped by the obstacle it records; (3, 5) hidden
        (2, 2): 1,  # up-left: obstacle, (1, 1) hidden
        (2, 4): 0,
        (1, 5): 0,  # up-right
        (4, 2): 0,
        (5, 1): 0,  # down-left
        (4, 4): 0,
        (5, 5): 0,  # down-right
    }
    assert seen == expected


def test_star_sensor_stops_at_the_border() -> None:
    grid = np.ones((5, 5), dtype=np.int8)
    grid[1:4, 1:4] = 0
    cells = {(r, c) for r, c, _ in star_view(grid, (1, 1), reach=2)}
    assert (0, 1) in cells
    assert (0, 0) in cells
    assert (1, 0) in cells
    assert all(0 <= r < 5 and 0 <= c < 5 for r, c in cells)


def test_broadcast_reaches_only_agents_within_range() -> None:
    grid = np.ones((31, 31), dtype=np.int8)
    grid[1:-1, 1:-1] = 0
    reach = broadcast_range(grid.shape)
    assert reach == 7  # 25 % of the larger side
    maze = Maze(grid, [(5, 5), (5, 12), (9, 8), (5, 13), (20, 20)])
    world = maze_world(maze, 5)
    assert world.neighbours(0, reach, "manhattan") == [1, 2]  # distances 7 and 7; (5, 13): 8
    assert world.neighbours(3, reach, "manhattan") == [1]  # (9, 8) is 9 away
    assert world.neighbours(4, reach, "manhattan") == []
    assert world.neighbours(2, 6, "euclid") == [0, 1]  # 5 and 5.7 away; (5, 13) is 6.4
    with pytest.raises(ValueError, match="metric"):
        world.neighbours(0, reach, "chebyshev")


def test_moves_respect_obstacles_and_other_agents() -> None:
    grid = np.ones((5, 5), dtype=np.int8)
    grid[1, 1:4] = 0
    world = maze_world(Maze(grid, [(1, 1), (1, 2)]), 2)
    assert isinstance(world, GridWorld) and world.exclusive
    east, south = direction_of(0, 1), direction_of(1, 0)
    assert east is not None and south is not None
    assert not world.move(0, east)  # occupied
    assert not world.move(0, south)  # obstacle
    assert world.move(1, east)
    assert world.move(0, east)
    assert [world.agent_cell(i) for i in range(2)] == [(1, 2), (1, 3)]
    with pytest.raises(ValueError, match="illegal move"):
        world.move(0, 4)  # a diagonal
    with pytest.raises(ValueError, match="starts"):
        maze_world(Maze(grid, [(1, 1)]), 2)


def test_an_exclusive_world_keeps_agents_apart_in_apply_too() -> None:
    grid = Grid([[0, 0, 0]])
    east = Action(move=direction_of(0, 1))
    shared = GridWorld(grid, (0, 0), starts=[(0, 0), (0, 1)])
    shared.apply(0, east)
    assert shared.positions == [1, 1]  # foraging agents share cells
    apart = GridWorld(grid, (0, 0), starts=[(0, 0), (0, 1)], exclusive=True)
    apart.apply(0, east)
    assert apart.positions == [0, 1]  # the move into the occupied cell failed
    apart.apply(1, east)
    apart.apply(0, east)
    assert apart.positions == [1, 2]
    with pytest.raises(ValueError, match="obstacle"):
        apart.apply(1, east)  # off the grid: an error, as in a shared world
    again = GridWorld.from_dict(apart.to_dict())
    assert again.exclusive
    again.apply(0, east)
    assert again.positions == [1, 2]
    with pytest.raises(ValueError, match="one cell"):
        GridWorld(grid, (0, 0), starts=[(0, 1), (0, 1)], exclusive=True)


def test_maze_file_round_trip(tmp_path: Path) -> None:
    maze = generate_maze(10, 0.5, np.random.default_rng(1), n_starts=4)
    path = tmp_path / "m.json"
    save_maze(path, maze)
    data = json.loads(path.read_text())
    assert set(data) == {"grid", "starts"}
    back = load_maze(path)
    assert np.array_equal(back.grid, maze.grid)
    assert back.starts == maze.starts


@pytest.mark.parametrize(
    ("content", "fault"),
    [
        ("{", ":1: not valid JSON: Expecting property name"),
        ('{"starts": []}', ": grid: is required (a list of rows)"),
        (
            '{"grid": [[1,1,1],[1,0],[1,1,1]]}',
            ": grid[1]: must be a row of 3 cells (as row 0), got 2",
        ),
        ('{"grid": [[1,1,1],[1,7,1],[1,1,1]]}', ": grid[1][1]: must be 0 or 1, got 7"),
        (
            '{"grid": [[1,1,1],[1,0,0],[1,1,1]]}',
            ": grid: must have obstacles (1) all along its border",
        ),
        (
            '{"grid": [[1,1,1],[1,0,1],[1,1,1]], "starts": [[0,0]]}',
            ": starts[0]: [0, 0] is an obstacle",
        ),
        (
            '{"grid": [[1,1,1],[1,0,1],[1,1,1]], "starts": [[1]]}',
            ": starts[0]: must be [row, col] (two integers), got [1]",
        ),
        (
            '{"grid": [[1,1,1],[1,0,1],[1,1,1]], "starts": [[5,1]]}',
            ": starts[0]: [5, 1] is outside the 3×3 grid",
        ),
        (
            '{"grid": [[1,1,1],[1,0,1],[1,1,1]], "starts": [[1,1],[1,1]]}',
            ": starts[1]: [1, 1] repeats starts[0]",
        ),
        (
            '{"grid": [[1,1,1],[1,0,1],[1,1,1]], "start": []}',
            ": start: unknown key (did you mean 'starts'?); known: grid, starts",
        ),
    ],
)
def test_bad_maze_files_name_the_file_and_fault(tmp_path: Path, content: str, fault: str) -> None:
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(MazeFileError) as err:
        load_maze(path)
    assert str(err.value).startswith(f"{path}{fault}"), err.value
    assert isinstance(err.value, ConfigError)


def test_missing_maze_file(tmp_path: Path) -> None:
    with pytest.raises(MazeFileError, match="cannot read"):
        load_maze(tmp_path / "nope.json")
