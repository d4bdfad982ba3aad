"""The impairment proxy delays, jitters, 'loses' and stalls as configured (measured on
127.0.0.1: no namespaces, no root, no process)."""

from __future__ import annotations

import asyncio
import statistics
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

import pytest

from mover._impair import CHUNK, Impairment, ImpairProxy


@asynccontextmanager
async def echo_through(
    proxy: ImpairProxy,
) -> AsyncIterator[tuple[asyncio.StreamReader, asyncio.StreamWriter]]:
    """An echo server behind ``proxy``, and a connection to it through the proxy."""

    async def echo(r: asyncio.StreamReader, w: asyncio.StreamWriter) -> None:
        while data := await r.read(65536):
            w.write(data)
            await w.drain()
        w.close()

    server = await asyncio.start_server(echo, "127.0.0.1", 0)
    proxy.target = server.sockets[0].getsockname()[:2]
    host, port = await proxy.start()
    reader, writer = await asyncio.open_connection(host, port)
    try:
        yield reader, writer
    finally:
        writer.close()
        await proxy.close()
        server.close()


async def round_trip(
    reader: asyncio.StreamReader, writer: asyncio.StreamWriter, n: int = 8
) -> float:
    t0 = time.monotonic()
    writer.write(b"x" * n)
    await asyncio.wait_for(reader.readexactly(n), 10)
    return time.monotonic() - t0


async def test_a_delay_each_way_adds_its_round_trip_and_jitter_stays_in_its_bounds() -> None:
    proxy = ImpairProxy(("127.0.0.1", 1), up=Impairment(0.05), down=Impairment(0.05), seed=1)
    async with echo_through(proxy) as (r, w):
        plain = [await round_trip(r, w) for _ in range(3)]
        proxy.up = proxy.down = Impairment(0.05, 0.02)
        jittered = [await round_trip(r, w) for _ in range(12)]
    print(
        f"50 ms each way: {[round(t * 1000) for t in plain]} ms; 50 ± 20 ms: "
        f"median {statistics.median(jittered) * 1000:.0f} ms, "
        f"{min(jittered) * 1000:.0f}-{max(jittered) * 1000:.0f} ms"
    )
    assert all(0.1 <= t < 0.3 for t in plain)  # upper bounds: slack for a loaded CI
    assert all(0.06 <= t < 0.4 for t in jittered)
    assert len({round(t, 3) for t in jittered}) > 5  # it does jitter
    assert proxy.stats.bytes_up == proxy.stats.bytes_down == 15 * 8


async def test_jitter_keeps_the_byte_order_and_an_end_comes_after_the_bytes() -> None:
    proxy = ImpairProxy(("127.0.0.1", 1), up=Impairment(0.02, 0.02), seed=2)
    async with echo_through(proxy) as (r, w):
        sent = b"".join(i.to_bytes(4, "big") for i in range(300))
        for i in range(0, len(sent), 4):
            w.write(sent[i : i + 4])
            await w.drain()
            if i % 40 == 0:
                await asyncio.sleep(0.001)  # separate chunks, each with its own draw
        w.write_eof()  # a half-close goes through, after the bytes before it
        got = await asyncio.wait_for(r.read(), 10)
    assert got == sent


async def test_a_lost_chunk_comes_a_retransmission_late_and_a_lost_retransmission_later() -> None:
    proxy = ImpairProxy(("127.0.0.1", 1), seed=3)
    async with echo_through(proxy) as (r, w):
        proxy.up = Impairment(loss=0.5, retransmit=0.04)
        took = [await round_trip(r, w) for _ in range(30)]
    # each round trip is 0, 1, 2, ... losses late: 0, 0.04, 0.04 + 0.08 = 0.12, 0.28 s, ...
    losses = [sum(t >= 0.04 * (2**k - 1) - 0.005 for k in range(1, 7)) for t in took]
    print(f"loss 50 %: losses per round trip {losses}; the proxy counted {proxy.stats.lost}")
    assert sum(losses) >= proxy.stats.lost  # every loss came late
    assert 8 <= proxy.stats.lost <= 60
    assert max(losses) >= 2  # a retransmission was lost too


async def test_a_stall_holds_everything_for_its_seconds_then_lets_it_through() -> None:
    proxy = ImpairProxy(("127.0.0.1", 1))
    async with echo_through(proxy) as (r, w):
        assert await round_trip(r, w) < 0.2
        proxy.stall(0.5)
        assert proxy.stalled
        took = await round_trip(r, w)
        assert not proxy.stalled
        after = await round_trip(r, w)
    print(f"stalled 0.5 s: round trip {took:.3f} s, then {after * 1000:.1f} ms")
    assert 0.45 <= took < 1.0
    assert after < 0.2


async def test_a_connection_buffers_at_most_its_cap() -> None:
    cap = 4 * CHUNK
    proxy = ImpairProxy(("127.0.0.1", 1), up=Impairment(0.01), max_buffer=cap)
    async with echo_through(proxy) as (r, w):
        proxy.stall(0.3)
        blob = bytes(range(256)) * 4096  # 1 MiB: far over the cap
        w.write(blob)
        got = await asyncio.wait_for(r.readexactly(len(blob)), 20)
    assert got == blob
    assert 0 < proxy.stats.max_buffered <= cap


def test_an_impairment_refuses_nonsense() -> None:
    with pytest.raises(ValueError, match="bad impairment"):
        Impairment(delay=-1)
    with pytest.raises(ValueError, match="bad impairment"):
        Impairment(loss=1.5)
