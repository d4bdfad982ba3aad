"""Range-limited broadcasts under spatial cells: the grid (no network), then nodes over real
zenoh in this process — a receiver that moves across cells keeps hearing what is in range, and
what is out of range is neither delivered nor, beyond the neighbourhood, even opened."""

from __future__ import annotations

import asyncio
import math
import random

import pytest

from mover import FixedLocator, Subscription, _cells
from mover._cells import CellSet, cell_of, cells_near, level
from tests.helpers.loopback import team_nodes


def test_levels_follow_the_ranges() -> None:
    assert level(1.0) == 0 and level(1.5) == 1 and level(2.0) == 1 and level(2.1) == 2
    assert level(0.0) == _cells.MIN_LEVEL and level(1e9) is None
    assert cell_of(-0.1, 3.9, 1) == "-1_1"


def test_cells_listened_to_cover_every_sender_in_range() -> None:
    rng = random.Random(5)
    for _ in range(2000):
        reach = rng.uniform(0.05, 20.0)
        lvl = level(reach)
        assert lvl is not None
        size = 2.0**lvl
        anchor = (rng.uniform(-50, 50), rng.uniform(-50, 50))
        listened = cells_near(*anchor, lvl, (1 + _cells.MARGIN) * size)
        # the receiver has moved less than MOVE cells since it chose them
        a = rng.uniform(0, 2 * math.pi)
        moved = rng.uniform(0, _cells.MOVE * size)
        me = (anchor[0] + moved * math.cos(a), anchor[1] + moved * math.sin(a))
        b, d = rng.uniform(0, 2 * math.pi), rng.uniform(0, reach)
        sender = (me[0] + d * math.cos(b), me[1] + d * math.sin(b))
        assert cell_of(*sender, lvl) in listened


class _Declared:
    def __init__(self, log: list[str], name: str) -> None:
        self.log, self.name = log, name
        log.append(f"+{name}")

    def undeclare(self) -> None:
        self.log.append(f"-{self.name}")


def test_cell_set_declares_new_cells_before_dropping_old_ones() -> None:
    log: list[str] = []
    cells = CellSet(lambda lvl, cell: _Declared(log, f"{lvl}:{cell}"))
    cells.add_level(1, (1.0, 1.0))
    first = cells.cells(1)
    assert "+1:0_0" in log and all(x[0] == "+" for x in log)
    cells.follow((1.3, 1.0))  # less than a quarter of a cell: nothing moves
    assert cells.moves == 1
    log.clear()
    cells.follow((3.0, 1.0))
    assert cells.moves == 2 and cells.cells(1) != first
    added = [x for x in log if x[0] == "+"]
    assert added and log[: len(added)] == added  # every new cell before any old one goes
    cells.close(undeclare=True)
    assert cells.levels == set()


async def _gather(sub: Subscription, out: list[tuple[int, float]]) -> None:
    async for m in sub:
        assert m.distance is not None
        out.append((int(m.data), m.distance))


@pytest.fixture
def short_grace(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_cells, "GRACE", 0.2)


@pytest.mark.usefixtures("short_grace")
async def test_a_receiver_moving_across_cells_hears_what_is_in_range() -> None:
    reach = 1.5  # level 1: cells of 2 m
    async with team_nodes(["s", "r"]) as (sender, receiver):
        sender.radio.locator = FixedLocator(0.3, 0.1)
        here = FixedLocator(-3.0, 0.0)
        receiver.radio.locator = here
        heard: list[tuple[int, float]] = []
        sub = receiver.subscribe("beacon")
        task = asyncio.create_task(_gather(sub, heard))
        in_range: list[int] = []
        for seq in range(400):  # 0.015 m a step: from x = -3 across three cell borders to x = 3
            here.x = -3.0 + 0.015 * seq
            if math.hypot(here.x - 0.3, here.y - 0.1) < reach - 0.1:
                in_range.append(seq)
            sender.broadcast_nowait("beacon", seq, range=reach, reliable=True)
            await asyncio.sleep(0.01)
        await asyncio.sleep(0.3)
        # after the grace the sender sends into its cell only, and the receiver followed
        cells = receiver._pubsub._topics["beacon"].cells
        assert cells is not None and cells.moves >= 3 and cells.levels == {1}
        sub.close()
        await task
        got = {seq for seq, _ in heard}
        assert sender.stats["sent.bc"] == 400
        assert set(in_range) <= got, sorted(set(in_range) - got)
        assert all(d <= reach for _, d in heard)


@pytest.mark.usefixtures("short_grace")
async def test_nothing_is_delivered_beyond_range_nor_sent_beyond_the_neighbourhood() -> None:
    async with team_nodes(["s", "near", "edge", "far"]) as (sender, near, edge, far):
        sender.radio.locator = FixedLocator(0.0, 0.0)
        near.radio.locator = FixedLocator(0.9, 0.0)
        edge.radio.locator = FixedLocator(1.1, 0.0)  # just out of range, in the next cell
        far.radio.locator = FixedLocator(40.0, 40.0)
        subs = {n.name: n.subscribe("ping") for n in (near, edge, far)}
        await asyncio.sleep(0.5)  # levels learnt, cells declared
        for seq in range(60):
            sender.broadcast_nowait("ping", seq, range=1.0, reliable=True)
            await asyncio.sleep(0.02)
        await asyncio.sleep(0.3)
        got = {name: [m.data for m in sub.drain()] for name, sub in subs.items()}
        assert got["near"] == list(range(60))
        assert got["edge"] == [] and got["far"] == []
        # the far receiver never even opened the frames sent after the grace
        assert far.radio.out_of_range < 60 and edge.radio.out_of_range == 60
        for sub in subs.values():
            sub.close()


async def test_flat_receivers_and_senders_still_hear_cell_ones(
    short_grace: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    async with team_nodes(["s", "flat"]) as (sender, flat):
        flat._pubsub.cells = False  # today's path: one key per topic, every frame opened
        sender.radio.locator = FixedLocator(0.0, 0.0)
        flat.radio.locator = FixedLocator(0.5, 0.0)
        sub = flat.subscribe("ping")
        await asyncio.sleep(0.3)
        for seq in range(30):
            sender.broadcast_nowait("ping", seq, range=1.0, reliable=True)
            await asyncio.sleep(0.02)
        await asyncio.sleep(0.3)
        assert [m.data for m in sub.drain()] == list(range(30))
        sub.close()
