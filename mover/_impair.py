"""A bad network in user space: a TCP proxy that delays, jitters, stalls and counts.

::

    proxy = ImpairProxy(("10.77.0.1", 7448), down=Impairment(0.05, 0.02, loss=0.1))
    host, port = await proxy.start(("10.77.0.1", 7449), netns=lab["a"].ns)
    proxy.stall(5.0)            # hold all traffic for 5 s
    await proxy.close()

For kernels without ``sch_netem`` (and for tests that need no root: on 127.0.0.1 it works as
any user). Every connection accepted is forwarded to ``target``; each direction (``up``: from
the client to the target, ``down``: back) has an :class:`Impairment`, read per chunk, so it may
be changed while connections are open.

What a chunk (one read, at most ``CHUNK`` bytes) goes through: a one-way ``delay`` plus a
uniform ``jitter`` of ± that much (clamped at 0); and it is 'lost' with probability ``loss``,
and so is each retransmission of it, each loss adding a retransmission timeout that doubles
(``retransmit``, then twice that, ...; at most ``MAX_RETRIES`` losses in a row). That is how
loss looks to an application over TCP: the bytes are never lost, they come late (Linux's least
timeout is 200 ms, the default here; it backs off by doubling), and everything behind them
waits too. At 10 % loss one chunk in a hundred is lost twice (0.6 s late) and one in a thousand
three times (1.4 s: past a 1 s lease). A chunk is never delivered before the one read before it
(per connection and direction: byte order is TCP's), so a short delay drawn after a long one
becomes the long one. :meth:`ImpairProxy.stall` holds every delivery for some seconds (a router
or a radio that goes silent; connections stay open). Each direction of a connection buffers at
most ``max_buffer`` bytes: past that the proxy stops reading (TCP's flow control pushes back on
the sender) until deliveries make room.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import random
import socket
import time
from dataclasses import dataclass, field

__all__ = ["CHUNK", "MAX_RETRIES", "ImpairProxy", "Impairment", "ProxyStats"]

CHUNK = 16384
"""Bytes read at most in one chunk (the unit that is delayed or 'lost')."""
MAX_RETRIES = 6
"""Losses in a row of one chunk at most (as TCP gives up on a link, eventually; 6 losses at
200 ms: 12.6 s late)."""


@dataclass(frozen=True)
class Impairment:
    """What one direction of a link does to each chunk: ``delay`` ± ``jitter`` seconds, and with
    probability ``loss`` another ``retransmit`` seconds, doubling for each loss in a row (see
    the module docstring)."""

    delay: float = 0.0
    jitter: float = 0.0
    loss: float = 0.0
    retransmit: float = 0.2

    def __post_init__(self) -> None:
        if min(self.delay, self.jitter, self.retransmit) < 0 or not 0 <= self.loss <= 1:
            raise ValueError(f"bad impairment {self}: times >= 0, loss from 0 to 1")

    def draw(self, rng: random.Random) -> tuple[float, int]:
        """Seconds one chunk is held, and how often it was 'lost' on the way (each loss adds a
        retransmission timeout, doubling)."""
        wait = max(0.0, self.delay + (rng.uniform(-self.jitter, self.jitter) if self.jitter else 0))
        lost = 0
        while self.loss > 0 and lost < MAX_RETRIES and rng.random() < self.loss:
            wait += self.retransmit * 2**lost
            lost += 1
        return wait, lost


@dataclass
class ProxyStats:
    """Counts since the proxy started: connections accepted, chunks read and bytes delivered
    each way, losses (a chunk lost twice counts twice), the longest a chunk was held by its
    draw (seconds; stalls aside) and the most bytes one direction of one connection held at
    once."""

    connections: int = 0
    chunks: int = 0
    bytes_up: int = 0
    bytes_down: int = 0
    lost: int = 0
    max_hold: float = 0.0
    max_buffered: int = 0


@dataclass
class _Pipe:
    """One direction of one connection: what was read and is not delivered yet."""

    queue: collections.deque[tuple[float, bytes]] = field(default_factory=collections.deque)
    buffered: int = 0
    due: float = 0.0  # the latest release time so far (order is kept)
    more: asyncio.Event = field(default_factory=asyncio.Event)  # something queued, or the end
    room: asyncio.Event = field(default_factory=asyncio.Event)  # below the buffer cap
    ended: bool = False


class ImpairProxy:
    """Forward TCP connections to ``target`` through :class:`Impairment` s ``up`` and ``down``
    (attributes: change them any time). ``seed`` makes the draws repeat."""

    def __init__(
        self,
        target: tuple[str, int],
        *,
        up: Impairment | None = None,
        down: Impairment | None = None,
        seed: int | None = None,
        max_buffer: int = 1 << 20,
    ) -> None:
        if max_buffer < CHUNK:
            raise ValueError(f"max_buffer must be at least {CHUNK} bytes")
        self.target = target
        self.up = up or Impairment()
        self.down = down or Impairment()
        self.max_buffer = max_buffer
        self.stats = ProxyStats()
        self._rng = random.Random(seed)
        self._netns: str | None = None
        self._server: asyncio.Server | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._writers: set[asyncio.StreamWriter] = set()
        self._stalled_until = 0.0
        self._resume = asyncio.Event()
        self._resume.set()

    async def start(
        self, listen: tuple[str, int] = ("127.0.0.1", 0), *, netns: str | None = None
    ) -> tuple[str, int]:
        """Listen on ``listen`` (in network namespace ``netns``, whose sockets also reach the
        target; see :mod:`mover._netlab`); the address and port listened on."""
        self._netns = netns
        sock = self._socket()
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind(listen)
            sock.listen(100)
            sock.setblocking(False)
            self._server = await asyncio.start_server(self._serve, sock=sock)
        except BaseException:
            sock.close()
            raise
        host, port = sock.getsockname()[:2]
        return str(host), int(port)

    def _socket(self) -> socket.socket:
        if self._netns is None:
            return socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        from ._netlab import socket_in

        return socket_in(self._netns)

    # -- faults --------------------------------------------------------------------------------

    def stall(self, seconds: float) -> None:
        """Hold every delivery, both ways, for ``seconds`` from now (longer if a stall already
        lasts longer); what is read meanwhile waits, up to the buffer cap."""
        until = time.monotonic() + seconds
        if until > self._stalled_until:
            self._stalled_until = until
            self._resume.clear()
            asyncio.get_running_loop().call_later(seconds, self._check_stall)

    def _check_stall(self) -> None:
        if time.monotonic() >= self._stalled_until - 1e-3:
            self._resume.set()

    @property
    def stalled(self) -> bool:
        """Whether deliveries are held now."""
        return not self._resume.is_set()

    # -- forwarding ----------------------------------------------------------------------------

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.stats.connections += 1
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        self._writers.add(writer)
        sock = self._socket()
        try:
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            await asyncio.get_running_loop().sock_connect(sock, self.target)
            t_reader, t_writer = await asyncio.open_connection(sock=sock)
        except OSError:
            sock.close()
            writer.close()
            self._writers.discard(writer)
            self._tasks.discard(task)
            return
        self._writers.add(t_writer)
        with contextlib.suppress(OSError):
            writer.get_extra_info("socket").setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            async with asyncio.TaskGroup() as tg:
                tg.create_task(self._direction(reader, t_writer, "up"))
                tg.create_task(self._direction(t_reader, writer, "down"))
        except* (OSError, ConnectionError):
            pass
        finally:
            for w in (writer, t_writer):
                w.close()
                self._writers.discard(w)
            self._tasks.discard(task)

    async def _direction(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, way: str
    ) -> None:
        pipe = _Pipe()
        pipe.room.set()
        deliver = asyncio.create_task(self._deliver(pipe, writer, way))
        try:
            while data := await reader.read(CHUNK):
                hold, lost = (self.up if way == "up" else self.down).draw(self._rng)
                self.stats.lost += lost
                self.stats.chunks += 1
                self.stats.max_hold = max(self.stats.max_hold, hold)
                pipe.due = max(pipe.due, time.monotonic() + hold)
                pipe.queue.append((pipe.due, data))
                pipe.buffered += len(data)
                self.stats.max_buffered = max(self.stats.max_buffered, pipe.buffered)
                pipe.more.set()
                if pipe.buffered + CHUNK > self.max_buffer:
                    pipe.room.clear()
                    await pipe.room.wait()
            pipe.ended = True
            pipe.more.set()
            await deliver
        finally:
            deliver.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await deliver

    async def _deliver(self, pipe: _Pipe, writer: asyncio.StreamWriter, way: str) -> None:
        while True:
            while not pipe.queue:
                if pipe.ended:
                    if writer.can_write_eof():
                        writer.write_eof()
                    return
                pipe.more.clear()
                await pipe.more.wait()
            due, data = pipe.queue[0]
            if (wait := due - time.monotonic()) > 0:
                await asyncio.sleep(wait)
            while not self._resume.is_set():
                await self._resume.wait()
            pipe.queue.popleft()
            writer.write(data)
            await writer.drain()
            pipe.buffered -= len(data)
            if way == "up":
                self.stats.bytes_up += len(data)
            else:
                self.stats.bytes_down += len(data)
            if pipe.buffered + CHUNK <= self.max_buffer:
                pipe.room.set()

    async def close(self) -> None:
        """Stop listening and drop every connection."""
        if self._server is not None:
            self._server.close()
        for w in list(self._writers):
            w.close()
        for t in list(self._tasks):
            t.cancel()
        if self._tasks:
            await asyncio.wait(list(self._tasks), timeout=2.0)
        self._resume.set()
