"""One agent's rounds (robots.explore.explore_rounds), driven by hand: what it asks, in order."""

from __future__ import annotations

import numpy as np
import pytest

from robots.explore import (
    STAY,
    Drive,
    Exchange,
    ExplorerAgent,
    Sense,
    View,
    explore_rounds,
    make_policy,
)

GRID = np.ones((5, 7), dtype=np.int8)
GRID[1:-1, 1:-1] = 0
STARTS = [(1, 1), (3, 5)]


def _agent(i: int = 0) -> ExplorerAgent:
    return ExplorerAgent(i, GRID.shape, STARTS, make_policy("nf"), np.random.default_rng(i))


def _view(cell: tuple[int, int], over: bool = False) -> View:
    r, c = cell
    cells = [(r + dr, c + dc, int(GRID[r + dr, c + dc])) for dr in (-1, 0, 1) for dc in (-1, 0, 1)]
    return View(cells, cell, over)


def test_a_lone_agent_senses_broadcasts_and_moves_without_relays() -> None:
    agent = _agent()
    plan = explore_rounds(agent, exchanges=3)
    assert next(plan) == Sense()
    ask = plan.send(_view((1, 1)))
    assert isinstance(ask, Exchange) and ask.index == 0
    assert ask.message["id"] == 0 and ask.message["pos"] == [1, 1]
    assert agent.known[2, 2] == 0  # the view was recorded before the broadcast
    ask = plan.send([])  # nobody heard: no relays
    assert isinstance(ask, Drive) and ask.move != STAY
    assert plan.send(None) == Sense()


def test_an_agent_that_heard_someone_relays_exchanges_minus_one_times() -> None:
    me, peer = _agent(0), _agent(1)
    plan = explore_rounds(me, exchanges=3)
    next(plan)
    plan.send(_view((1, 1)))
    peer.observe(seen_cells=_view((3, 5)).cells, position=(3, 5))
    ask = plan.send([peer.outgoing_message()])
    assert me.known[3, 6] == 1 and 1 in me.peers  # what the peer saw, and the peer
    for k in (1, 2):
        assert isinstance(ask, Exchange) and ask.index == k
        assert set(ask.message) == {"id", "free", "obstacle"}  # a relay: map cells only
        ask = plan.send([peer.relay_message()])
    assert isinstance(ask, Drive)


@pytest.mark.parametrize("exchanges", [1, 2])
def test_fewer_exchanges_fewer_relays(exchanges: int) -> None:
    plan = explore_rounds(_agent(), exchanges=exchanges)
    next(plan)
    plan.send(_view((1, 1)))
    asks = [plan.send([_agent(1).outgoing_message()])]
    while isinstance(asks[-1], Exchange):
        asks.append(plan.send([]))
    assert [type(a) for a in asks] == [Exchange] * (exchanges - 1) + [Drive]


def test_the_rounds_end_with_a_view_that_is_over_and_count_the_moves() -> None:
    agent = _agent()
    plan = explore_rounds(agent)
    next(plan)
    for _ in range(2):
        plan.send(_view(agent.position))
        ask = plan.send([])
        assert isinstance(ask, Drive)
        assert plan.send(None) == Sense()
    with pytest.raises(StopIteration) as end:
        plan.send(_view((1, 2), over=True))
    assert end.value.value == 2
    assert agent.position == (1, 2)  # the last view was still recorded


def test_at_least_one_exchange() -> None:
    with pytest.raises(ValueError, match="at least 1"):
        explore_rounds(_agent(), exchanges=0)
