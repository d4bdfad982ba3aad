"""RPC round trip and broadcast throughput of mover against raw zenoh, measured in one run.

    python bench/rpc.py [--rounds N] [--flood-seconds S] [--receivers 10]

(a) raw zenoh get -> queryable (zenoh's default callback, reply in the callback),
(a') the fair baseline for any asyncio framework: raw zenoh with the smallest asyncio hand-off
on both sides (the queryable hands the query to the server's loop, which replies; the caller
awaits a future that the reply callback resolves on its loop), and
(b) a mover call (sealed envelopes, argument check, procedure run on the callee's asyncio loop),
between the same two processes over the same zenoh link, at 64 B, 64 KiB and 1 MiB, interleaved
in rounds so that machine noise hits all alike. Then delivered messages per second of
(c) raw zenoh put -> subscriber handed into asyncio (coalesced wake-ups) and
(d) mover range-limited broadcast (every receiver within range, so each verifies, filters and
delivers), one sender to ``--receivers`` receiver processes, reliable (congestion control BLOCK)
in both. The last line is one JSON object of the figures.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import sys
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import zenoh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mover import FixedLocator, Node, NodeConfig, TeamCredentials
from mover._config import free_port

RAW_KEY = "bench/raw/echo"
LOOP_KEY = "bench/raw/loop"
FLOOD_KEY = "bench/raw/flood"


# -- child processes --------------------------------------------------------------------------


async def serve() -> None:
    """The callee: a raw queryable and a mover node on the same zenoh session."""
    async with Node("server", TeamCredentials.from_env(), config=NodeConfig.from_env()) as node:

        def raw(query: Any) -> None:
            with query:
                query.reply(RAW_KEY, query.payload, express=True)

        queryable = node.zenoh_session.declare_queryable(RAW_KEY, raw)
        loop = asyncio.get_running_loop()

        def reply_on_loop(query: Any) -> None:
            with query:
                query.reply(LOOP_KEY, query.payload, express=True)

        def handed(query: Any) -> None:  # one hop into the loop, the reply from there
            loop.call_soon_threadsafe(reply_on_loop, query)

        looped = node.zenoh_session.declare_queryable(LOOP_KEY, handed)

        def echo(data: bytes) -> bytes:
            return data

        node.export(echo)
        print("READY", flush=True)
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)
        queryable.undeclare()
        looped.undeclare()


async def _loop_get(session: Any, payload: bytes) -> bytes:
    """A raw get whose reply is handed into this loop, awaited as a future."""
    loop = asyncio.get_running_loop()
    future: asyncio.Future[bytes] = loop.create_future()

    def on_reply(reply: Any) -> None:
        if reply.ok is not None:
            data = reply.ok.payload.to_bytes()

            def settle() -> None:
                if not future.done():
                    future.set_result(data)

            loop.call_soon_threadsafe(settle)

    session.get(
        LOOP_KEY,
        on_reply,
        payload=payload,
        express=True,
        consolidation=zenoh.ConsolidationMode.NONE,
        timeout=10.0,
    )
    return await asyncio.wait_for(future, 10)


async def receive(name: str, mode: str) -> None:
    """A flood receiver: counts what reaches its asyncio loop, raw or through mover."""
    loop = asyncio.get_running_loop()
    count = 0
    first = last = 0.0
    async with Node(
        name,
        TeamCredentials.from_env(),
        config=NodeConfig.from_env(),
        locator=FixedLocator(1.0, 0.0),
    ) as node:
        if mode == "raw":
            items: deque[Any] = deque()
            pending = [False]

            def drain() -> None:
                nonlocal count, first, last
                pending[0] = False
                n = len(items)
                for _ in range(n):
                    items.popleft()
                if n:
                    now = time.perf_counter()
                    if count == 0:
                        first = now
                    count += n
                    last = now

            def on_sample(sample: Any) -> None:
                items.append(sample)
                if not pending[0]:
                    pending[0] = True
                    loop.call_soon_threadsafe(drain)

            raw = node.zenoh_session.declare_subscriber(FLOOD_KEY, on_sample)
            close: Callable[[], object] = raw.undeclare
        else:
            sub = node.subscribe("flood", maxlen=10_000_000)

            async def consume() -> None:
                nonlocal count, first, last
                while True:
                    await sub.get()
                    batch = 1 + len(sub.drain())
                    now = time.perf_counter()
                    if count == 0:
                        first = now
                    count += batch
                    last = now

            consumer = asyncio.create_task(consume())
            close = sub.close

        def stats() -> list[float]:
            return [count, last - first]

        node.export(stats)
        print("READY", flush=True)
        await loop.run_in_executor(None, sys.stdin.read)
        if mode != "raw":
            consumer.cancel()
        close()


# -- the coordinator --------------------------------------------------------------------------


async def spawn(args: list[str], env: dict[str, str]) -> asyncio.subprocess.Process:
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        __file__,
        *args,
        env=env,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
    )
    assert proc.stdout is not None
    async with asyncio.timeout(30):
        while not (await proc.stdout.readline()).startswith(b"READY"):
            pass
    return proc


async def stop(procs: list[asyncio.subprocess.Process]) -> None:
    for p in procs:
        if p.returncode is None:
            p.kill()
        await p.wait()


def pct(samples: list[float], q: int) -> float:
    return statistics.quantiles(samples, n=100, method="inclusive")[q - 1] * 1000.0


async def measure_rpc(node: Node, rounds: int) -> dict[str, Any]:
    session = node.zenoh_session
    out: dict[str, Any] = {}
    for label, size, per_round in (("64B", 64, 200), ("64KiB", 65536, 40), ("1MiB", 1 << 20, 5)):
        payload = os.urandom(size)
        raw: list[float] = []
        looped: list[float] = []
        mover: list[float] = []
        for _ in range(3):  # warm-up
            session.get(
                RAW_KEY, payload=payload, consolidation=zenoh.ConsolidationMode.NONE, express=True
            ).recv()
            await node.call("server", "echo", payload)
        for _ in range(rounds):
            for _ in range(per_round):
                t = time.perf_counter()
                reply = session.get(
                    RAW_KEY,
                    payload=payload,
                    express=True,
                    consolidation=zenoh.ConsolidationMode.NONE,
                ).recv()
                raw.append(time.perf_counter() - t)
                assert reply.ok is not None and len(reply.ok.payload.to_bytes()) == size
            for _ in range(per_round):
                t = time.perf_counter()
                assert len(await _loop_get(session, payload)) == size
                looped.append(time.perf_counter() - t)
            for _ in range(per_round):
                t = time.perf_counter()
                echoed = await node.call("server", "echo", payload, timeout=10)
                mover.append(time.perf_counter() - t)
                assert len(echoed) == size
        out[label] = {
            "raw_p50": pct(raw, 50),
            "raw_p99": pct(raw, 99),
            "asyncio_p50": pct(looped, 50),
            "mover_p50": pct(mover, 50),
            "mover_p99": pct(mover, 99),
            "n": len(raw),
        }
    return out


async def measure_flood(
    node: Node, env: dict[str, str], mode: str, receivers: int, seconds: float
) -> dict[str, float]:
    procs = await asyncio.gather(
        *(
            spawn(["--role", "receive", "--name", f"rx{i}", "--mode", mode], env)
            for i in range(receivers)
        )
    )
    try:
        await node.membership.wait_for({f"rx{i}" for i in range(receivers)}, timeout=30)
        await asyncio.sleep(1.0)  # subscriptions propagate
        payload = os.urandom(64)
        sent = 0
        publisher = node.zenoh_session.declare_publisher(
            FLOOD_KEY, congestion_control=zenoh.CongestionControl.BLOCK
        )
        deadline = time.perf_counter() + seconds
        while time.perf_counter() < deadline:
            for _ in range(200):
                if mode == "raw":
                    publisher.put(payload)
                else:
                    node.broadcast_nowait("flood", payload, range=10.0, reliable=True)
            sent += 200
            await asyncio.sleep(0)
        publisher.undeclare()
        await asyncio.sleep(1.5)  # let the receivers drain
        stats = [await node.call(f"rx{i}", "stats", timeout=10) for i in range(receivers)]
        rates = [c / d for c, d in stats if d > 0]
        delivered = sum(c for c, _ in stats)
        return {
            "msgs_per_s": sum(rates),
            "sent": sent,
            "delivered": delivered,
            "delivered_fraction": delivered / max(1, sent * receivers),
        }
    finally:
        await stop(list(procs))


async def coordinate(args: argparse.Namespace) -> None:
    team = TeamCredentials.generate("bench")
    port = free_port()
    env = dict(os.environ)
    env.update(team.env())
    env.update(NodeConfig(connect=(f"tcp/127.0.0.1:{port}",)).env())
    async with Node(
        "client",
        team,
        config=NodeConfig(listen=(f"tcp/127.0.0.1:{port}",)),
        locator=FixedLocator(0.0, 0.0),
    ) as node:
        server = await spawn(["--role", "serve"], env)
        try:
            await node.membership.wait_for({"server"}, timeout=30)
            rpc = await measure_rpc(node, args.rounds)
        finally:
            await stop([server])
        flood = {
            mode: await measure_flood(node, env, mode, args.receivers, args.flood_seconds)
            for mode in ("raw", "mover")
        }
    for label, r in rpc.items():
        print(
            f"RPC {label:>5}: raw get->queryable p50 {r['raw_p50']:.3f} ms p99 "
            f"{r['raw_p99']:.3f} ms | mover call p50 {r['mover_p50']:.3f} ms p99 "
            f"{r['mover_p99']:.3f} ms | ratio p50 {r['mover_p50'] / r['raw_p50']:.2f} "
            f"(n={r['n']} each) | raw+asyncio hand-offs p50 {r['asyncio_p50']:.3f} ms, "
            f"ratio {r['mover_p50'] / r['asyncio_p50']:.2f}"
        )
    for mode, f in flood.items():
        print(
            f"flood {mode:>5}: {f['msgs_per_s']:,.0f} delivered msgs/s over {args.receivers} "
            f"receivers ({f['delivered_fraction']:.1%} of {f['sent']:,} sent x receivers)"
        )
    figures = {
        "rpc_p50_ms_raw": round(rpc["64B"]["raw_p50"], 4),
        "rpc_p99_ms_raw": round(rpc["64B"]["raw_p99"], 4),
        "rpc_p50_ms_mover": round(rpc["64B"]["mover_p50"], 4),
        "rpc_p99_ms_mover": round(rpc["64B"]["mover_p99"], 4),
        "rpc_p50_ms_raw_64KiB": round(rpc["64KiB"]["raw_p50"], 4),
        "rpc_p50_ms_mover_64KiB": round(rpc["64KiB"]["mover_p50"], 4),
        "rpc_ratio_64B": round(rpc["64B"]["mover_p50"] / rpc["64B"]["raw_p50"], 3),
        "rpc_ratio_64KiB": round(rpc["64KiB"]["mover_p50"] / rpc["64KiB"]["raw_p50"], 3),
        "rpc_p50_ms_asyncio": round(rpc["64B"]["asyncio_p50"], 4),
        "rpc_p50_ms_asyncio_1MiB": round(rpc["1MiB"]["asyncio_p50"], 4),
        "rpc_p50_ms_mover_1MiB": round(rpc["1MiB"]["mover_p50"], 4),
        "rpc_ratio_vs_asyncio_64B": round(rpc["64B"]["mover_p50"] / rpc["64B"]["asyncio_p50"], 3),
        "rpc_ratio_vs_asyncio_1MiB": round(
            rpc["1MiB"]["mover_p50"] / rpc["1MiB"]["asyncio_p50"], 3
        ),
        "broadcast_msgs_per_s_raw": round(flood["raw"]["msgs_per_s"]),
        "broadcast_msgs_per_s_mover": round(flood["mover"]["msgs_per_s"]),
        "broadcast_ratio": round(flood["mover"]["msgs_per_s"] / flood["raw"]["msgs_per_s"], 3),
    }
    print(json.dumps(figures))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--role", choices=("coordinate", "serve", "receive"), default="coordinate")
    p.add_argument("--name", default="rx")
    p.add_argument("--mode", choices=("raw", "mover"), default="mover")
    p.add_argument("--rounds", type=int, default=10)
    p.add_argument("--receivers", type=int, default=10)
    p.add_argument("--flood-seconds", type=float, default=3.0)
    args = p.parse_args()
    if args.role == "serve":
        asyncio.run(serve())
    elif args.role == "receive":
        asyncio.run(receive(args.name, args.mode))
    else:
        asyncio.run(coordinate(args))


if __name__ == "__main__":
    main()
