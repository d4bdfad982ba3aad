"""Nothing is sealed or sent under a key nobody listens to: a publisher whose key no subscriber
has matched once its first :data:`mover._radio.SETTLE` seconds are over counts what it would have
sent (``unheard.bc``) and sends no frame (``sent.bc_frames`` stays); once a subscriber appears,
frames go again. Nodes over real zenoh on 127.0.0.1 in this process."""

from __future__ import annotations

import asyncio

import pytest

from mover import FixedLocator, Node, _cells, _radio
from tests.helpers.loopback import team_nodes

SETTLE = 0.5  # the publishers' settle time and the senders' grace here (1 s by default)


@pytest.fixture(autouse=True)
def short_settle(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MOVER_RADIO_CELLS", raising=False)  # cells on, whatever the shell says
    monkeypatch.setattr(_radio, "SETTLE", SETTLE)
    monkeypatch.setattr(_cells, "GRACE", SETTLE)


async def _send(node: Node, topic: str, n: int, reach: float | None = None) -> None:
    for seq in range(n):
        node.broadcast_nowait(topic, seq, range=reach, reliable=True)
        await asyncio.sleep(0.01)  # one turn of the loop each: one frame each


def _sent(node: Node) -> tuple[int, int, int]:
    return node.stats["sent.bc"], node.stats["sent.bc_frames"], node.stats["unheard.bc"]


async def test_a_topic_nobody_listens_to_costs_no_frame_until_someone_does() -> None:
    async with team_nodes(["s", "r"]) as (sender, receiver):
        await _send(sender, "quiet", 5)  # a new publisher sends while it settles
        assert _sent(sender) == (5, 5, 0)
        await asyncio.sleep(SETTLE + 0.1)
        await _send(sender, "quiet", 20)
        assert _sent(sender) == (5, 5, 20)  # counted, neither sealed nor sent
        sub = receiver.subscribe("quiet")
        tries = 0
        while sender.stats["sent.bc_frames"] == 5:  # until the publisher sees the subscriber
            assert tries < 100, f"no frame went within a second of a subscriber: {_sent(sender)}"
            await _send(sender, "quiet", 1)
            tries += 1
        await _send(sender, "quiet", 10)
        await asyncio.sleep(0.3)
        sent, frames, unheard = _sent(sender)
        assert sent + unheard == 5 + 20 + tries + 10 and frames == sent
        assert unheard < 20 + tries  # frames go once the match is seen
        heard = [m.data for m in sub.drain()]
        assert heard[-10:] == list(range(10))  # and arrive
        sub.close()


async def test_a_sender_in_a_cell_nobody_listens_to_sends_nothing() -> None:
    async with team_nodes(["s", "far"]) as (sender, far):
        sender.radio.locator = FixedLocator(0.0, 0.0)
        far.radio.locator = FixedLocator(40.0, 40.0)
        sub = far.subscribe("ping")
        await asyncio.sleep(0.1)
        # team-wide while the grace lasts (the far receiver listens there, so frames go) ...
        await _send(sender, "ping", 5, reach=1.0)
        assert _sent(sender) == (5, 5, 0)
        await asyncio.sleep(SETTLE + 0.1)
        # ... then under the sender's cell: sent while its publisher settles, then not at all
        await _send(sender, "ping", 5, reach=1.0)
        await asyncio.sleep(SETTLE + 0.1)
        before = _sent(sender)
        await _send(sender, "ping", 30, reach=1.0)
        sent, frames, unheard = _sent(sender)
        assert (sent, frames) == before[:2] and unheard == before[2] + 30
        assert [m.data for m in sub.drain()] == []  # out of range all along
        sub.close()


async def test_a_topic_whose_last_listener_left_stops_costing_frames() -> None:
    """A publisher found matched is trusted for ``MATCHED_FOR`` seconds without asking zenoh
    again; once its listener has gone and that time is over, what it would send is counted
    as unheard."""
    async with team_nodes(["s", "r"]) as (sender, receiver):
        sub = receiver.subscribe("brief")
        await asyncio.sleep(SETTLE + 0.1)  # past the settle time: matching is asked of zenoh
        await _send(sender, "brief", 5)
        assert _sent(sender) == (5, 5, 0)  # matched: sent
        sub.close()
        await asyncio.sleep(_radio.MATCHED_FOR + 0.5)
        await _send(sender, "brief", 10)
        sent, frames, unheard = _sent(sender)
        assert sent + unheard == 15 and frames == sent
        assert unheard >= 5, f"still sent to a topic nobody listens to: {_sent(sender)}"
