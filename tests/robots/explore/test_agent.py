"""The agent: its map, messages (only what changed), regions (section III)."""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np
import pytest

from robots.explore import (
    FREE,
    OBSTACLE,
    UNKNOWN,
    ExplorerAgent,
    make_policy,
    make_team,
    unexplored_in_view,
    voronoi_partition,
)
from robots.explore._voronoi import balanced_partition
from sim_hw.grid import generate_maze, star_view


def test_voronoi_regions_cover_free_cells_without_overlap() -> None:
    maze = generate_maze(30, 0.85, np.random.default_rng(5))
    seeds = maze.starts[:6]
    label = voronoi_partition(maze.grid == 0, seeds)
    assert (label[maze.grid == 0] >= 0).all()  # every free cell has exactly one owner
    assert (label[maze.grid == 1] == -1).all()
    assert [label[s] for s in seeds] == list(range(6))
    # the agents' own regions (from the initial map) partition the inner cells
    team = make_team("cu-lvp", maze.shape, seeds, 1)
    masks = np.array([a.in_region() for a in team]).reshape(6, *maze.shape)
    assert (masks.sum(axis=0)[1:-1, 1:-1] == 1).all()
    assert masks.sum(axis=0)[0].sum() == 0


def test_voronoi_is_geodesic() -> None:
    grid = np.ones((5, 7), dtype=bool)
    grid[:, 3] = False
    grid[4, 3] = True  # the wall has a gap at the bottom
    label = voronoi_partition(grid, [(0, 2), (0, 4)])
    assert label[0, 0] == 0
    assert label[4, 2] == 0
    assert label[0, 6] == 1
    assert label[4, 3] == 0  # tie at the gap goes to the lower index


def test_balanced_partition_evens_region_sizes() -> None:
    open_room = np.ones((9, 9), dtype=bool)
    for seeds, plain, balanced in (
        ([(0, 0), (4, 4)], [23, 58], [35, 46]),
        ([(0, 0), (3, 3), (8, 8)], [20, 46, 15], [31, 25, 25]),
        ([(0, 0), (0, 2)], [18, 63], [18, 63]),  # seeds in a row: additive weights can't split
    ):
        assert np.bincount(voronoi_partition(open_room, seeds).ravel()).tolist() == plain
        label = balanced_partition(open_room, seeds)
        assert np.bincount(label.ravel()).tolist() == balanced
        assert [label[s] for s in seeds] == list(range(len(seeds)))
    # in random mazes' starts (8 agents) the largest region shrinks, each region stays whole
    maze = generate_maze(30, 0.85, np.random.default_rng(5), n_starts=8)
    inner = np.ones(maze.shape, dtype=bool)
    inner[0, :] = inner[-1, :] = inner[:, 0] = inner[:, -1] = False
    plain_label = voronoi_partition(inner, maze.starts)
    label = balanced_partition(inner, maze.starts)
    assert (label[inner] >= 0).all() and (label[~inner] == -1).all()
    assert np.bincount(label[inner]).max() < np.bincount(plain_label[inner]).max()
    for i, seed in enumerate(maze.starts):  # connected: one wavefront from the seed reaches all
        assert (voronoi_partition(label == i, [seed]) == 0).sum() == (label == i).sum()


def test_cu_lvp_agents_take_balanced_regions_baselines_plain_ones() -> None:
    maze = generate_maze(30, 0.85, np.random.default_rng(5), n_starts=8)
    inner = np.ones(maze.shape, dtype=bool)
    inner[0, :] = inner[-1, :] = inner[:, 0] = inner[:, -1] = False
    lvp = make_team("cu-lvp", maze.shape, maze.starts, 1)[3]
    nf = make_team("nf", maze.shape, maze.starts, 1)[3]
    assert (lvp.in_region() == (balanced_partition(inner, maze.starts) == 3).ravel()).all()
    assert (nf.in_region() == (voronoi_partition(inner, maze.starts) == 3).ravel()).all()
    old = make_team("cu-lvp", maze.shape, maze.starts, 1, partition="voronoi")[3]
    assert (old.in_region() == nf.in_region()).all()  # the earlier reading, kept as an option
    with pytest.raises(ValueError, match="unknown partition 'square'"):
        make_policy("cu-lvp", "square")


def test_messages_carry_only_changes_and_merge() -> None:
    grid = np.ones((9, 9), dtype=np.int8)
    grid[1:-1, 1:-1] = 0
    starts = [(2, 2), (6, 6)]
    a, b = make_team("cu-lvp", grid.shape, starts, 3)
    seen_a = star_view(grid, (2, 2))
    inner_a = {(r, c) for r, c, _ in seen_a if 0 < r < 8 and 0 < c < 8}
    a.observe(seen_cells=seen_a, position=(2, 2))
    first = msgpack.unpackb(msgpack.packb(a.outgoing_message()))
    assert len(first["free"]) // 2 == len(inner_a) == 12  # uint16 each; border known already
    again = a.outgoing_message()
    assert again["free"] == b""
    assert again["obstacle"] == b""
    b.observe(heard_messages=[first])
    assert b.known[2, 2] == FREE
    assert b.known[0, 0] == OBSTACLE
    assert b.regions == frozenset({1})  # its own region stays first,
    assert b.merged == frozenset({0})  # the region of the agent met is merged in
    assert b.peers[0].pos == a.pos
    # b heard a newcomer: its next message is its whole map, so a catches up
    seen_b = star_view(grid, (6, 6))
    inner_b = {(r, c) for r, c, _ in seen_b if 0 < r < 8 and 0 < c < 8}
    b.observe(seen_cells=seen_b, position=(6, 6))
    full = b.outgoing_message()
    assert len(full["free"]) // 2 == len(inner_a | inner_b) == 23
    b.observe(heard_messages=[first])
    assert b.outgoing_message()["free"] == b""


def test_unexplored_in_view_counts_the_star() -> None:
    known = np.full((7, 7), UNKNOWN, dtype=np.int8)
    known[0], known[-1], known[:, 0], known[:, -1] = OBSTACLE, OBSTACLE, OBSTACLE, OBSTACLE
    assert unexplored_in_view(known)[3, 3] == 16
    known[3, 4] = OBSTACLE  # known, and blocks the right ray: (3, 5) not counted either
    known[2, 3] = FREE  # seen, not counted; the ray goes on to (1, 3)
    assert unexplored_in_view(known)[3, 3] == 13


def test_agent_never_plans_into_a_known_obstacle() -> None:
    grid = np.ones((7, 7), dtype=np.int8)
    grid[1:-1, 1:-1] = 0
    grid[3, 2:5] = 1
    agent = ExplorerAgent(0, grid.shape, [(2, 3)], make_policy("nf"), np.random.default_rng(0))
    for _ in range(30):
        agent.observe(seen_cells=star_view(grid, agent.position), heard_messages=[])
        dr, dc = agent.decide()
        r, c = agent.position
        assert grid[r + dr, c + dc] == 0
        agent.observe(position=(r + dr, c + dc))
    assert not (agent.known[1:-1, 1:-1] == UNKNOWN).any()


def test_cu_lvp_goals_stay_inside_the_agents_regions() -> None:
    from robots.grid_hal import direction_of
    from sim_hw.grid import broadcast_range, maze_world

    maze = generate_maze(30, 0.85, np.random.default_rng(11), n_starts=6)
    world = maze_world(maze, 6)
    team = make_team("cu-lvp", maze.shape, maze.starts[:6], 4)
    reach = broadcast_range(maze.shape)
    for _ in range(60):
        for i, a in enumerate(team):
            cell = world.agent_cell(i)
            a.observe(seen_cells=star_view(maze.grid, cell), position=cell)
        msgs = [msgpack.unpackb(msgpack.packb(a.outgoing_message())) for a in team]
        for i, a in enumerate(team):
            a.observe(heard_messages=[msgs[j] for j in world.neighbours(i, reach, "manhattan")])
            move = a.decide()
            if a.goal is not None:
                assert a.region_of[a.goal] in a.regions | a.merged
                assert a.known.ravel()[a.goal] == UNKNOWN
            d = direction_of(*move)
            if d is not None:
                world.move(i, d)


def test_public_face() -> None:
    import robots.explore as explore

    assert all(hasattr(explore, name) for name in explore.__all__)


def test_unexplored_in_view_counts_each_ray_up_to_its_first_obstacle() -> None:
    from robots.grid_hal import STAR_RAYS as RAYS  # what robots.explore._sensing looks along

    rng = np.random.default_rng(2)
    known = rng.choice([UNKNOWN, FREE, OBSTACLE], size=(12, 12)).astype(np.int8)
    known[0], known[-1], known[:, 0], known[:, -1] = OBSTACLE, OBSTACLE, OBSTACLE, OBSTACLE
    full = unexplored_in_view(known)
    for r in range(1, 11):
        for c in range(1, 11):
            expected = 0
            for dr, dc in RAYS:  # walk each ray cell by cell
                for k in (1, 2):
                    v = known[r + k * dr, c + k * dc]
                    if v == OBSTACLE:
                        break
                    expected += v == UNKNOWN
            assert full[r, c] == expected


def test_a_path_of_the_most_gain_among_the_shortest() -> None:
    from robots.explore._grid import passable_mask, path_to, wavefront

    known = np.full((5, 6), FREE, dtype=np.int8)
    known[0], known[-1], known[:, 0], known[:, -1] = OBSTACLE, OBSTACLE, OBSTACLE, OBSTACLE
    width = 6
    start, goal = 1 * width + 1, 3 * width + 4
    gain = [0] * known.size
    gain[3 * width + 2] = 5  # the bottom-left way in is worth more
    _, parent, _ = wavefront(passable_mask(known), start, width, gain=gain)
    path = path_to(parent, start, goal)
    assert len(path) == 5  # still a shortest path
    assert 3 * width + 2 in path
    gain[3 * width + 2], gain[1 * width + 4] = 0, 7  # now the top-right way
    _, parent, _ = wavefront(passable_mask(known), start, width, gain=gain)
    path = path_to(parent, start, goal)
    assert len(path) == 5 and 1 * width + 4 in path


def _chain(exchanges: int) -> list[ExplorerAgent]:
    """Three agents in a corridor, a-b and b-c in range, a-c not; one round of talk."""
    grid = np.ones((3, 25), dtype=np.int8)
    grid[1, 1:-1] = 0
    starts = [(1, 2), (1, 9), (1, 16)]
    team = make_team("cu-lvp", grid.shape, starts, 1)
    hears = {0: [1], 1: [0, 2], 2: [1]}  # range 7 cells
    for a in team:
        a.observe(seen_cells=star_view(grid, a.position), position=a.position)
    msgs = [msgpack.unpackb(msgpack.packb(a.outgoing_message())) for a in team]
    for i, a in enumerate(team):
        a.observe(heard_messages=[msgs[j] for j in hears[i]])
    for _ in range(exchanges - 1):
        relays = [msgpack.unpackb(msgpack.packb(a.relay_message())) for a in team]
        for i, a in enumerate(team):
            a.hear_relay([relays[j] for j in hears[i]])
    return team


def test_relays_carry_news_along_a_chain_in_one_round() -> None:
    a, _, c = _chain(exchanges=1)
    assert c.known[1, 1] == UNKNOWN  # one exchange: c hears b, who knew only itself
    a, _, c = _chain(exchanges=2)
    assert c.known[1, 1] == FREE and c.known[1, 3] == FREE  # what a saw, through b
    assert a.known[1, 18] == FREE  # and back
    assert c.peers.keys() == {1}  # positions and goals are still those heard directly
    # nothing new: the next relay of each is empty
    assert all(m["free"] == b"" for m in (x.relay_message() for x in _chain(3)[::2]))


def test_a_message_passes_on_the_news_that_changed_and_all_of_it_to_a_newcomer() -> None:
    starts = [(1, 1), (1, 4), (1, 7)]
    # the agents in range of each other, round by round: all three; a0 away, twice; a0 back
    # and a2 away
    rounds = [[0, 1, 2], [1, 2], [1, 2], [0, 1]]

    def passed_on(news: str) -> list[list[int]]:
        """The agents whose news a1's message passes on, each round and after the last."""
        team = make_team("cu-lvp", (9, 9), starts, 3, news=news)
        passed = []
        for group in [*rounds, []]:
            out = [_wire(a.outgoing_message()) for a in team]
            passed.append(sorted(e[0] for e in out[1].get("news", [])))
            for i, a in enumerate(team):
                a.observe(heard_messages=[out[j] for j in group if j != i] if i in group else [])
        return passed

    # what a1 heard in the round before (its news of a0 stops changing once a0 is away, and
    # is not passed on again); after the last round, a0 is a newcomer to a1: all of it, a2's
    # unchanged news included
    assert passed_on("on") == [[], [0, 2], [2], [2], [0, 2]]
    assert passed_on("whole") == [[], [0, 2], [0, 2], [0, 2], [0, 2]]
    assert passed_on("off") == [[]] * 5


def test_agents_sharing_a_region_split_it() -> None:
    grid = np.ones((3, 25), dtype=np.int8)
    grid[1, 1:-1] = 0
    starts = [(1, 3), (1, 21)]  # two regions: columns 1-12 and 13-23

    def shared(holder_at: int) -> tuple[list[int], list[int]]:
        helper, holder = make_team("cu-lvp", grid.shape, starts, 1)
        helper.observe(seen_cells=star_view(grid, (1, 8)), position=(1, 8))
        holder.observe(seen_cells=star_view(grid, (1, holder_at)), position=(1, holder_at))
        helper.set_regions({1})  # its own region done, it helps with the holder's
        messages = [msgpack.unpackb(msgpack.packb(a.outgoing_message())) for a in (helper, holder)]
        helper.observe(heard_messages=messages[1:])
        holder.observe(heard_messages=messages[:1])
        return (
            [int(k) % 25 for k in helper.candidates().nonzero()[0]],
            [int(k) % 25 for k in holder.candidates().nonzero()[0]],
        )

    # the holder, heard at 19, sees 17-21: of the unknown 13-16 and 22-23 only 13 is nearer
    # the helper at 8; the holder keeps the rest
    assert shared(19) == ([13], [14, 15, 16, 22, 23])
    # holder at 16: no unknown cell of the region is nearer the helper, so it takes them all
    assert shared(16) == ([13, 19, 20, 21, 22, 23], [13, 19, 20, 21, 22, 23])


def _wire(msg: dict[str, Any]) -> dict[str, Any]:
    """A message as the hearer gets it: packed and unpacked."""
    out: dict[str, Any] = msgpack.unpackb(msgpack.packb(msg))
    return out


def test_news_of_agents_out_of_range_is_passed_on() -> None:
    starts = [(1, 1), (1, 4), (1, 7)]
    team = make_team("cu-lvp", (9, 9), starts, 3)
    a0, a1, a2 = team
    for a in team:
        a.observe(heard_messages=[])  # round 1: nobody in range
    a1.observe(heard_messages=[_wire(a0.outgoing_message())])  # round 2: a1 hears a0
    a2.observe(heard_messages=[])
    a2.observe(heard_messages=[_wire(a1.outgoing_message())])  # round 3: a2 hears a1 only
    assert a2.recent_cells(10) == [a0.pos]  # a0, heard by a1 a round ago; a1 is in range
    assert a2.recent_cells(0) == []  # ... but not news of this round
    assert a2._helpers(0) == 1 and a2._helpers(1) == 1 and a2._helpers(2) == 0
    # older news does not replace newer: a2 hears a0 itself, then a1's stale word of it
    a2.observe(heard_messages=[_wire(a0.outgoing_message())])
    stale = _wire(a1.relay_message() | {"news": [[0, 2, 99, [5]]]})
    a2.hear_relay([stale])
    assert a2._news[0] == (4, a0.pos, (0,))
    # the baselines pass no news on
    nf = make_team("nf", (9, 9), starts, 3)
    nf[1].observe(heard_messages=[_wire(nf[0].outgoing_message())])
    assert "news" not in nf[1].outgoing_message()
