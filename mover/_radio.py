"""Range-limited publish/subscribe, and the neighbour table it feeds.

A broadcast carries the sender's position at send time (from its locator) and the range. Each
receiver compares it with its own position and drops what is out of range, so a message reaches
exactly the members within ``range`` metres, as a radio or an infrared link would. A delivered
message carries the sender, the distance and the bearing — the direction of the sender in the
receiver's own frame (radians, counter-clockwise from the receiver's heading, in (-pi, pi]), as
ARGoS's range-and-bearing sensor and Buzz's ``neighbors`` give. An optional :class:`RadioModel`
adds a per-link drop probability and Gaussian range and bearing noise from a seeded generator.
``range=None`` is plain team-wide pub/sub (distance and bearing are still filled in when both
ends have positions).

:class:`PubSub` is a node's sending and receiving side: broadcasts made in one turn of the event
loop leave together, one sealed frame per topic (framing: :func:`mover._wire.broadcast_frames`),
and each received frame is opened, judged fresh and fanned out to the topic's subscriptions.
"""

from __future__ import annotations

import asyncio
import math
import os
import random
import time
from collections import deque
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, cast

import zenoh

from . import _cells, _keys
from ._bridge import sample_size
from ._cells import CellSet, Undeclarable
from ._exceptions import PayloadTooLarge, WireError
from ._futures import running_loop
from ._wire import SessionUnknown, broadcast_frames, pack, read_broadcast

if TYPE_CHECKING:
    from ._membership import Membership
    from ._session import SessionState


PUBLISHERS = 64  # publishers kept per node (cells visited, topics), least recently used dropped
SETTLE = 1.0  # seconds a new publisher sends before its matching status is trusted
MATCHED_FOR = 0.25
"""Seconds a publisher found matched is taken as matched without asking zenoh again (asking
costs ~1 µs and a hand-off each flush; a subscriber that left is sent to this much longer)."""
FOLLOW = 0.1  # seconds between checks of a listening node's cell subscriptions


class Locator(Protocol):
    """Where this robot is: ``(x, y, heading)`` in metres and radians, or None if unknown."""

    def position(self) -> tuple[float, float, float] | None:
        """This robot's ``(x, y, heading)`` now, or None while it is not known."""
        ...


@dataclass
class FixedLocator:
    """A locator that stays where it is put (tests, workstations, fixed beacons)."""

    x: float
    y: float
    heading: float = 0.0

    def position(self) -> tuple[float, float, float] | None:
        """The fixed ``(x, y, heading)``."""
        return (self.x, self.y, self.heading)


@dataclass(frozen=True)
class RadioModel:
    """Imperfections of the range-limited link, applied by each receiver."""

    drop: float = 0.0  # probability that a message in range is lost
    range_noise: float = 0.0  # standard deviation of the distance, metres
    bearing_noise: float = 0.0  # standard deviation of the bearing, radians
    seed: int | None = None


@dataclass(frozen=True, slots=True)
class Message:
    """A delivered broadcast."""

    sender: str
    topic: str
    data: Any
    distance: float | None
    bearing: float | None
    sent: float  # the sender's timestamp (Unix seconds)


@dataclass(frozen=True, slots=True)
class Neighbour:
    """A member heard recently."""

    name: str
    distance: float | None
    bearing: float | None
    seen: float  # local monotonic time when last heard


class Subscription:
    """Messages on one topic, as an async iterator; close it (or use ``async with``) when done."""

    def __init__(self, topic: str, maxlen: int, on_close: Any) -> None:
        self.topic = topic
        self._items: deque[Message] = deque(maxlen=maxlen)
        self._waiter: asyncio.Future[None] | None = None
        self._closed = False
        self._on_close = on_close
        self.dropped = 0  # messages lost because the reader fell ``maxlen`` behind

    def _put(self, messages: list[Message]) -> None:
        room = (self._items.maxlen or 0) - len(self._items)
        if len(messages) > room:
            self.dropped += len(messages) - room
        self._items.extend(messages)
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)

    def get_nowait(self) -> Message | None:
        """The next message if one is waiting, else None."""
        return self._items.popleft() if self._items else None

    def drain(self) -> list[Message]:
        """Every message waiting now."""
        items = list(self._items)
        self._items.clear()
        return items

    async def get(self, timeout: float | None = None) -> Message:
        """The next message; TimeoutError after ``timeout`` s, StopAsyncIteration if closed."""
        if self._items:  # one waits: no timer, no context (a tick's frame is often here)
            return self._items.popleft()
        async with asyncio.timeout(timeout):
            while not self._items:
                if self._closed:
                    raise StopAsyncIteration
                self._waiter = running_loop().create_future()
                try:
                    await self._waiter
                finally:
                    self._waiter = None
        return self._items.popleft()

    def __aiter__(self) -> AsyncIterator[Message]:
        return self

    async def __anext__(self) -> Message:
        return await self.get()

    def close(self) -> None:
        """Stop receiving; a pending ``get`` ends with StopAsyncIteration."""
        if self._closed:
            return
        self._closed = True
        self._on_close(self)
        if self._waiter is not None and not self._waiter.done():
            self._waiter.set_result(None)

    async def __aenter__(self) -> Subscription:
        return self

    async def __aexit__(self, *exc: object) -> None:
        self.close()


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _wrap(angle: float) -> float:
    a = math.fmod(angle + math.pi, 2 * math.pi)
    if a <= 0:
        a += 2 * math.pi
    return a - math.pi


class Radio:
    """The receiving side's range filter, noise model and neighbour table."""

    def __init__(self, locator: Locator | None, model: RadioModel | None) -> None:
        self.locator = locator
        self.model = model or RadioModel()
        self._rng = random.Random(self.model.seed)
        self._neighbours: dict[str, Neighbour] = {}
        self.out_of_range = 0
        self.lost = 0
        self.malformed = 0  # authentic items with a wrong position or range

    def position(self) -> tuple[float, float, float] | None:
        return self.locator.position() if self.locator is not None else None

    def receive(
        self, sender: str, topic: str, data: Any, where: Any, reach: Any, sent: float
    ) -> Message | None:
        """The message as this receiver gets it, or None if it does not reach us."""
        got = self.receive_all(sender, topic, [[data, where, reach]], sent)
        return got[0] if got else None

    def receive_all(self, sender: str, topic: str, items: list[Any], sent: float) -> list[Message]:
        """The messages of one frame (``[data, where, range]`` items) that reach us."""
        me = self.position()
        model = self.model
        out: list[Message] = []
        last_where: Any = None
        distance = bearing = None
        for item in items:
            if not (isinstance(item, list) and len(item) == 3):
                continue
            data, where, reach = item
            if not (reach is None or _is_number(reach)) or not (
                where is None
                or (isinstance(where, list) and len(where) >= 2 and all(map(_is_number, where)))
            ):
                self.malformed += 1  # authentic but wrong: skip it, keep the rest
                continue
            if where != last_where:  # a burst from one place: compute once
                last_where = where
                distance = bearing = None
                if me is not None and where is not None:
                    dx, dy = float(where[0]) - me[0], float(where[1]) - me[1]
                    distance = math.hypot(dx, dy)
                    bearing = _wrap(math.atan2(dy, dx) - me[2])
            d, b = distance, bearing
            if reach is not None:
                if d is None or d > float(reach):
                    self.out_of_range += 1
                    continue
                if model.drop and self._rng.random() < model.drop:
                    self.lost += 1
                    continue
                if model.range_noise:
                    d = max(0.0, d + self._rng.gauss(0.0, model.range_noise))
                if model.bearing_noise and b is not None:
                    b = _wrap(b + self._rng.gauss(0.0, model.bearing_noise))
            out.append(Message(sender, topic, data, d, b, sent))
        if out:
            last = out[-1]
            self._neighbours[sender] = Neighbour(
                sender, last.distance, last.bearing, time.monotonic()
            )
        return out

    def neighbours(self, max_age: float = 1.0) -> dict[str, Neighbour]:
        """Members heard within the last ``max_age`` seconds."""
        horizon = time.monotonic() - max_age
        return {n: v for n, v in self._neighbours.items() if v.seen >= horizon}

    def forget(self, name: str) -> None:
        self._neighbours.pop(name, None)


class _Topic:
    """One subscribed topic: its subscriptions and the zenoh subscribers behind them."""

    def __init__(self) -> None:
        self.subs: list[Subscription] = []
        self.declared: list[Undeclarable] = []  # team-wide key, level tokens' subscriber
        self.cells: CellSet | None = None


@dataclass(slots=True)
class _Publisher:
    """A declared publisher: since when, and when a subscriber was last found matching it."""

    pub: zenoh.Publisher
    since: float
    matched: float = -math.inf


class PubSub:
    """A node's broadcasts and subscriptions (see the module).

    Range-limited broadcasts go under their sender's cell (:mod:`mover._cells`) unless ``cells``
    is False (the environment variable ``MOVER_RADIO_CELLS=off``): then every broadcast goes
    under the topic's team-wide key and every receiver opens every frame, as a flat team does; a
    flat receiver still hears cell senders and the other way round. Nothing is sealed or sent
    under a key that no subscriber has matched for :data:`SETTLE` seconds.
    """

    def __init__(self, state: SessionState, radio: Radio, team: Membership) -> None:
        self.state = state
        self.radio = radio
        self.team = team
        self.cells = os.environ.get("MOVER_RADIO_CELLS", "on") != "off"
        self._topics: dict[str, _Topic] = {}
        self._publishers: dict[tuple[str, bool, bool], _Publisher] = {}
        self._outbox: dict[tuple[str, str, bool, bool], list[bytes]] = {}
        # (topic, level) -> the liveliness token saying this node sends there, and since when
        self._levels: dict[tuple[str, int], tuple[zenoh.LivelinessToken, float]] = {}
        self._flush_scheduled = False
        self._follow_timer: asyncio.TimerHandle | None = None

    def broadcast(
        self, topic: str, data: Any, range: float | None, reliable: bool, express: bool
    ) -> None:
        """Queue ``data`` on ``topic`` (see ``Node.broadcast_nowait``); it leaves at the end of
        this turn of the loop."""
        if range is not None and range < 0:
            raise ValueError("range must be >= 0")
        where = self.radio.position()
        item = pack([data, list(where) if where else None, range])
        if len(item) > self.state.sealer.max_size // 2:
            raise PayloadTooLarge(f"broadcast of {len(item)} bytes is over the limit")
        key = self._key(topic, range, where)
        box = self._outbox.get((key, topic, reliable, express))
        if box is None:
            _keys.check_topic(topic)
            box = self._outbox[(key, topic, reliable, express)] = []
        box.append(item)
        if not self._flush_scheduled:
            self._flush_scheduled = True
            running_loop().call_soon(self.flush)

    def _key(self, topic: str, reach: float | None, where: Any) -> str:
        """The key a broadcast goes under: its sender's cell, or the topic's team-wide key."""
        team = self.state.team
        lvl = None if reach is None or where is None or not self.cells else _cells.level(reach)
        if lvl is None:
            return _keys.broadcast(team, topic)
        token = self._levels.get((topic, lvl))
        if token is None:
            _keys.check_topic(topic)
            key = _keys.broadcast_level(team, lvl, self.state.name, topic)
            token = self._levels[(topic, lvl)] = (
                self.state.session().liveliness().declare_token(key),
                time.monotonic(),
            )
        if time.monotonic() - token[1] < _cells.GRACE:
            return _keys.broadcast(team, topic)
        return _keys.broadcast_cell(team, lvl, _cells.cell_of(where[0], where[1], lvl), topic)

    def flush(self) -> None:
        """Send what was queued (at the end of the turn, or as the node closes)."""
        self._flush_scheduled = False
        state = self.state
        if not state.is_open:
            return
        self.follow()
        outbox, self._outbox = self._outbox, {}
        for (key, topic, reliable, express), items in outbox.items():
            pub = self._publisher(key, reliable, express)
            if pub is None:
                state.stats["unheard.bc"] += len(items)
                continue
            for frame in broadcast_frames(state.sealer, topic, items):
                pub.put(frame)
                state.stats["sent.bc_frames"] += 1
            state.stats["sent.bc"] += len(items)

    def _publisher(self, key: str, reliable: bool, express: bool) -> zenoh.Publisher | None:
        """The publisher for ``key``, or None if no subscriber has matched it for a while."""
        entry = self._publishers.pop((key, reliable, express), None)
        now = time.monotonic()
        if entry is None:
            congestion = zenoh.CongestionControl.BLOCK if reliable else zenoh.CongestionControl.DROP
            pub = self.state.session().declare_publisher(
                key, congestion_control=congestion, express=express
            )
            entry = _Publisher(pub, now)
            if len(self._publishers) >= PUBLISHERS:  # the least recently used goes
                oldest = next(iter(self._publishers))
                self._publishers.pop(oldest).pub.undeclare()
        self._publishers[(key, reliable, express)] = entry  # most recently used last
        if now - entry.since < SETTLE or now - entry.matched < MATCHED_FOR:
            return entry.pub
        # the stub says matching_status() -> bool; zenoh 1.10 has a property with .matching
        if cast(Any, entry.pub).matching_status.matching:
            entry.matched = now
            return entry.pub
        return None

    def subscribe(self, topic: str, maxlen: int) -> Subscription:
        """A new subscription to ``topic`` (one set of zenoh subscribers per topic, shared)."""
        _keys.check_topic(topic)
        sub = Subscription(topic, maxlen, self._unsubscribe)
        entry = self._topics.get(topic)
        if entry is None:
            entry = self._topics[topic] = self._declare(topic)
        entry.subs.append(sub)
        return sub

    def _declare(self, topic: str) -> _Topic:
        session, door, team = self.state.session(), self.state.door(), self.state.team
        on_frame = door.callback(self.on_frame, droppable=True, size=sample_size)
        entry = _Topic()
        entry.declared.append(session.declare_subscriber(_keys.broadcast(team, topic), on_frame))
        if not self.cells:  # every cell of every level
            key = _keys.broadcast_cell(team, "*", "*", topic)
            entry.declared.append(session.declare_subscriber(key, on_frame))
            return entry

        def declare(lvl: int, cell: str) -> Undeclarable:
            key = _keys.broadcast_cell(team, lvl, cell, topic)
            return session.declare_subscriber(key, on_frame)

        cells = entry.cells = CellSet(declare)

        def on_token(sample: zenoh.Sample) -> None:
            if sample.kind == zenoh.SampleKind.PUT and self._topics.get(topic) is entry:
                cells.add_level(_keys.level_of(str(sample.key_expr)), self._where())
                self._follow_soon()

        key = _keys.broadcast_level(team, "*", "*", topic)
        entry.declared.append(
            session.liveliness().declare_subscriber(key, door.callback(on_token), history=True)
        )
        return entry

    def _where(self) -> tuple[float, float] | None:
        where = self.radio.position()
        return None if where is None else (where[0], where[1])

    def follow(self) -> None:
        """Move the cell subscriptions to where this node is now."""
        where = self._where()
        for entry in self._topics.values():
            if entry.cells is not None:
                entry.cells.follow(where)

    def _follow_soon(self) -> None:
        """Follow this node's moves every :data:`FOLLOW` seconds while it listens to cells."""
        if self._follow_timer is None:
            self._follow_timer = asyncio.get_running_loop().call_later(FOLLOW, self._on_timer)

    def _on_timer(self) -> None:
        self._follow_timer = None
        if self.state.is_open and any(e.cells and e.cells.levels for e in self._topics.values()):
            self.follow()
            self._follow_soon()

    def _unsubscribe(self, sub: Subscription) -> None:
        entry = self._topics.get(sub.topic)
        if entry is None or sub not in entry.subs:
            return
        entry.subs.remove(sub)
        if not entry.subs:
            del self._topics[sub.topic]
            self._undeclare(entry, self.state.is_open)

    @staticmethod
    def _undeclare(entry: _Topic, is_open: bool) -> None:
        if entry.cells is not None:
            entry.cells.close(is_open)
        if is_open:
            for declared in entry.declared:
                declared.undeclare()

    def on_frame(self, sample: zenoh.Sample) -> None:
        """A broadcast frame arrived (on the loop)."""
        state = self.state
        try:
            env = state.opener.open(sample.payload.to_bytes())
            if env.sender == state.name:
                return
            topic, items = read_broadcast(env)
            state.peers.admit(env, state.name, state.sealer.epoch)
        except SessionUnknown as exc:
            # a member this node has not verified yet (it just joined, or we did): ask for its
            # hello; what it sent before that does not count
            state.stats["refused.unverified"] += 1
            self.team.verify_soon(exc.envelope.sender)
            return
        except WireError as exc:
            state.stats["refused"] += 1
            state.faults.warn("bc", f"dropped a broadcast on {sample.key_expr}: {exc}")
            return
        entry = self._topics.get(topic)
        if entry is None:
            return
        messages = self.radio.receive_all(env.sender, topic, items, env.timestamp)
        if messages:
            for sub in entry.subs:
                sub._put(messages)
        state.stats["recv.bc"] += len(messages)

    def close(self) -> None:
        """Send what is queued, then close every subscription."""
        self.flush()
        if self._follow_timer is not None:
            self._follow_timer.cancel()
            self._follow_timer = None
        for entry in list(self._topics.values()):
            for sub in list(entry.subs):
                sub.close()

    def closed(self) -> None:
        """The session is gone: forget its publishers and level tokens."""
        self._publishers.clear()
        self._levels.clear()
