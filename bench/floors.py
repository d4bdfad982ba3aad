"""What this machine allows under issue 25's targets: the same work with mover taken out.

    python bench/floors.py [--quick] [--parts world,procs,rss]

Each figure is a floor any design on these parts (CPython, asyncio, pymunk, zenoh) pays, so a
target above its floor cannot be met here by changing mover; the figures of ``bench/sim.py``
and ``bench/team.py`` are read against them.

(world) for 10, 50, 200 and 1000 robots placed as ``bench/sim.py`` places them: the
pymunk physics of a tick alone (``World.step`` with the sensing left out:
``floor_world_physics_ms_N``), and the least an in-process HAL with one coroutine a robot
costs in lock-step, one future per robot per tick resolved and awaited, nothing else
(``floor_world_wake_ms_N``); ``floor_rtf_world_N`` is the real-time factor of the two
together, with no sensing, no readings and no controller.
(procs) N = 10 and 50 processes in lock-step over raw zenoh on 127.0.0.1, in the topology
``mover up`` picks (``mover._up.needs_router``: a peer mesh, or every process a client of one
router process): a hub publishes a frame of N x 200 bytes a tick, each process hands it into
its asyncio loop (one ``call_soon_threadsafe``, the fair hand-off of ``bench/rpc.py``) and
puts a 100-byte command; the hub hands each into its loop and publishes the next frame once
it has all N. No sealing, no msgpack, no physics: ``floor_rtf_procs_N`` (ticks of 0.1 s).
(rss) the RSS (MB) of a Python process with asyncio and one zenoh session (listening on
loopback, a subscriber and a queryable declared), one second after opening
(``floor_rss_mb``); the same with ``cryptography``'s AES-GCM and msgpack loaded and used once
(``floor_rss_aead_mb``).

The last line is one JSON object of these keys (and ``procs_topology_N``).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

import zenoh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
# (mover and sim_hw are imported where used: the memory probe's process must load neither)

TICK = 0.1
FRAME_KEY, COMMAND_KEY = "floor/frame", "floor/command"


# -- the world in process ---------------------------------------------------------------------


def physics_ms(n: int, ticks: int) -> float:
    """Milliseconds a tick of ``n`` robots' physics costs (``World.step``, sensing left out)."""
    from sim_hw import World, WorldSpec
    from sim_hw.continuous._worldfile import parse_robot

    side = max(6.0, math.sqrt(n * 4.0))  # bench/sim.py's arena: ~4 m² a robot
    world = World(WorldSpec(size=(side, side), name=f"floor-{n}"), seed=1)
    spec = parse_robot({"sonar": {"rays": 8, "max_range": 3.0}, "camera": False},
                       world.spec.robot, "floor")  # fmt: skip
    for i in range(n):
        world.add_robot(f"r{i:03d}", spec)
        world.set_command(f"r{i:03d}", {"v": 0.4, "w": 0.3 if i % 2 else -0.3})
    world._measure_all = lambda robots: None  # type: ignore[method-assign]  # physics only
    world.step()
    t0 = time.perf_counter()
    for _ in range(ticks):
        world.step()
    return (time.perf_counter() - t0) / ticks * 1000.0


async def wake_ms(n: int, ticks: int) -> float:
    """Milliseconds a tick costs ``n`` coroutines in lock-step: each hands in, awaits its own
    future; the last one in resolves them all."""
    loop = asyncio.get_running_loop()
    futures: list[asyncio.Future[None]] = []
    handed = 0

    def hand_in() -> asyncio.Future[None]:
        nonlocal handed, futures
        future = loop.create_future()
        futures.append(future)
        handed += 1
        if handed == n:  # the tick: answer everyone
            done, futures, handed = futures, [], 0
            for f in done:
                f.set_result(None)
        return future

    async def robot() -> None:
        for _ in range(ticks):
            await hand_in()

    t0 = time.perf_counter()
    await asyncio.gather(*(robot() for _ in range(n)))
    return (time.perf_counter() - t0) / ticks * 1000.0


async def world_floors(sizes: list[int], scale: float) -> dict[str, float]:
    out: dict[str, float] = {}
    for n in sizes:
        ticks = max(20, round(scale * 20000 / n))
        phys, wake = physics_ms(n, ticks), await wake_ms(n, ticks)
        out[f"floor_world_physics_ms_{n}"] = round(phys, 3)
        out[f"floor_world_wake_ms_{n}"] = round(wake, 3)
        out[f"floor_rtf_world_{n}"] = round(TICK * 1000.0 / (phys + wake), 1)
        print(f"world floor, {n:4d} robots: physics {phys:.3f} ms + wake-ups {wake:.3f} ms "
              f"a tick: {out[f'floor_rtf_world_{n}']}x real time", flush=True)  # fmt: skip
    return out


# -- processes over raw zenoh -----------------------------------------------------------------


def _session(endpoint: str, role: str) -> zenoh.Session:
    conf = zenoh.Config()
    conf.insert_json5("scouting/multicast/enabled", "false")
    if role == "router":
        conf.insert_json5("mode", '"router"')
        conf.insert_json5("listen/endpoints", json.dumps([endpoint]))
    elif role == "client":
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    elif role == "hub":  # the peer mesh's listener
        conf.insert_json5("listen/endpoints", json.dumps([endpoint]))
    else:  # a peer of the mesh: it connects to the hub and learns the others from it
        conf.insert_json5("listen/endpoints", '["tcp/127.0.0.1:0"]')
        conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    return zenoh.open(conf)


def _into_loop(loop: asyncio.AbstractEventLoop, on_item: Any) -> Any:
    """A zenoh callback that hands each sample's bytes into ``loop``."""

    def callback(sample: zenoh.Sample) -> None:
        data = sample.payload.to_bytes()
        with contextlib.suppress(RuntimeError):  # the loop closed: the run is over
            loop.call_soon_threadsafe(on_item, data)

    return callback


async def walker(endpoint: str, role: str, index: int) -> None:
    """One process: a command for every frame of a later tick, until the frame says stop."""
    loop = asyncio.get_running_loop()
    done = loop.create_future()
    session = _session(endpoint, role)
    pub = session.declare_publisher(
        COMMAND_KEY, congestion_control=zenoh.CongestionControl.BLOCK, express=True
    )
    last = -1
    pad = bytes(92)

    def on_frame(data: bytes) -> None:
        nonlocal last
        tick = int.from_bytes(data[:4], "big")
        if tick == 0xFFFFFFFF:
            if not done.done():
                done.set_result(None)
            return
        if tick > last or tick == 0:
            last = tick
            pub.put(tick.to_bytes(4, "big") + index.to_bytes(4, "big") + pad)

    sub = session.declare_subscriber(FRAME_KEY, _into_loop(loop, on_frame))
    print("READY", flush=True)
    await asyncio.wait([done, _orphaned()], timeout=300, return_when=asyncio.FIRST_COMPLETED)
    sub.undeclare()
    session.close()


async def hub(n: int, ticks: int, endpoint: str, role: str) -> float:
    """Ticks of 0.1 s per wall second of ``n`` processes in lock-step (``role``: this
    process's place in the topology)."""
    loop = asyncio.get_running_loop()
    session = _session(endpoint, role)
    pub = session.declare_publisher(
        FRAME_KEY, congestion_control=zenoh.CongestionControl.BLOCK, express=True
    )
    body = bytes(200 * n)
    seen: set[int] = set()
    tick = 0
    all_in: asyncio.Future[None] = loop.create_future()

    def on_command(data: bytes) -> None:
        if int.from_bytes(data[:4], "big") == tick:
            seen.add(int.from_bytes(data[4:8], "big"))
            if len(seen) == n and not all_in.done():
                all_in.set_result(None)

    sub = session.declare_subscriber(COMMAND_KEY, _into_loop(loop, on_command))
    try:
        while not all_in.done():  # tick 0 until every process hears and is heard
            pub.put(tick.to_bytes(4, "big") + body)
            await asyncio.wait([all_in], timeout=0.05)
        t0 = time.perf_counter()
        for tick in range(1, ticks + 1):
            seen.clear()
            all_in = loop.create_future()
            pub.put(tick.to_bytes(4, "big") + body)
            await asyncio.wait_for(all_in, 30)
        wall = time.perf_counter() - t0
        for _ in range(3):
            pub.put((0xFFFFFFFF).to_bytes(4, "big"))
    finally:
        sub.undeclare()
    await asyncio.sleep(0.2)
    session.close()
    return ticks * TICK / wall


async def procs_floor(n: int, ticks: int) -> tuple[float, str]:
    from mover._config import free_port
    from mover._up import needs_router  # the topology rule of `mover up`

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    router = needs_router(n + 1)  # the processes and the hub, as bench/sim.py counts
    children = []
    try:
        if router:
            children.append(await _spawn(["router", endpoint, "router", "0"]))
        role = "client" if router else "peer"
        hub_role = "client" if router else "hub"
        run = asyncio.ensure_future(hub(n, ticks, endpoint, hub_role))
        await asyncio.sleep(0.3)  # the hub (or router) listens first
        children += await asyncio.gather(
            *(_spawn(["walker", endpoint, role, str(i)]) for i in range(n))
        )
        rtf = await asyncio.wait_for(run, 120 + 2 * n)
    finally:
        for child in children:
            if child.returncode is None:
                child.kill()
            await child.wait()
    return rtf, "router" if router else "peer"


def _orphaned() -> asyncio.Future[None]:
    """Done once this child's stdin closes: the benchmark that started it is gone (even
    killed), and the child ends too."""
    loop = asyncio.get_running_loop()
    gone: asyncio.Future[None] = loop.create_future()

    def end() -> None:
        if not gone.done():
            gone.set_result(None)

    def read() -> None:
        sys.stdin.buffer.read()
        with contextlib.suppress(RuntimeError):  # (the loop closed: the child ends anyway)
            loop.call_soon_threadsafe(end)

    threading.Thread(target=read, daemon=True).start()  # (a daemon: no join at exit)
    return gone


async def _spawn(args: list[str]) -> asyncio.subprocess.Process:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, __file__, *args, cwd=ROOT,
        stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE,
    )  # fmt: skip
    assert proc.stdout is not None
    try:
        async with asyncio.timeout(60):
            while not (await proc.stdout.readline()).startswith(b"READY"):
                pass
    except BaseException:  # not up (or the run was interrupted): it is ended here
        proc.kill()
        await proc.wait()
        raise
    return proc


async def router(endpoint: str) -> None:
    session = _session(endpoint, "router")
    print("READY", flush=True)
    try:
        await _orphaned()
    finally:
        session.close()


# -- memory -----------------------------------------------------------------------------------


async def rss_probe(aead: bool) -> None:
    """Print this process's RSS (kB) a second after opening a zenoh session."""
    if aead:
        import msgpack
        from cryptography.hazmat.primitives.ciphers.aead import AESGCM

        AESGCM(os.urandom(32)).encrypt(bytes(12), msgpack.packb([1, "x"]), b"")
    session = _session("tcp/127.0.0.1:0", "hub")
    session.declare_subscriber("floor/x/**", lambda sample: None)
    session.declare_queryable("floor/y/**", lambda query: None)
    await asyncio.sleep(1.0)
    for line in Path("/proc/self/smaps_rollup").read_text().splitlines():
        if line.startswith("Rss:"):
            print(line.split()[1], flush=True)
    os._exit(0)  # (the session's threads are not waited for: the figure is printed)


async def rss_floor(aead: bool) -> float:
    args = ["rss", "aead" if aead else "bare"]
    proc = await asyncio.create_subprocess_exec(
        sys.executable, __file__, *args, stdout=asyncio.subprocess.PIPE, cwd=ROOT
    )
    out, _ = await asyncio.wait_for(proc.communicate(), 60)
    return int(out.split()[-1]) / 1024


PARTS = ("world", "procs", "rss")


def _parts(text: str) -> set[str]:
    """``--parts``: some of PARTS, comma-separated."""
    parts = {p.strip() for p in text.split(",") if p.strip()}
    unknown = sorted(parts - set(PARTS))
    if unknown or not parts:
        raise argparse.ArgumentTypeError(f"{text!r}: parts are some of {', '.join(PARTS)}")
    return parts


async def main(args: argparse.Namespace) -> dict[str, Any]:
    scale = 0.3 if args.quick else 1.0
    parts = args.parts
    out: dict[str, Any] = {}
    if "world" in parts:
        out.update(await world_floors([10, 50, 200, 1000], scale))
    if "procs" in parts:
        for n, seconds in ((10, 30.0), (50, 10.0)):
            rtf, topology = await procs_floor(n, round(seconds * scale / TICK))
            out[f"floor_rtf_procs_{n}"] = round(rtf, 1)
            out[f"procs_topology_{n}"] = topology
            print(f"raw zenoh lock-step, {n} processes ({topology}): {rtf:.1f}x real time",
                  flush=True)  # fmt: skip
    if "rss" in parts:
        for aead, key in ((False, "floor_rss_mb"), (True, "floor_rss_aead_mb")):
            out[key] = round(await rss_floor(aead), 1)
        bare, aead = out["floor_rss_mb"], out["floor_rss_aead_mb"]
        print(f"a Python process with one zenoh session: {bare} MB RSS; with "
              f"cryptography's AES-GCM and msgpack: {aead} MB", flush=True)  # fmt: skip
    return out


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] in ("walker", "router", "rss"):
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the run's: it ends us
        what = sys.argv[1]
        if what == "walker":
            asyncio.run(walker(sys.argv[2], sys.argv[3], int(sys.argv[4])))
        elif what == "router":
            asyncio.run(router(sys.argv[2]))
        else:
            asyncio.run(rss_probe(sys.argv[2] == "aead"))
        sys.exit(0)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="30 %% of the ticks")
    parser.add_argument(
        "--parts", type=_parts, default=set(PARTS), help="comma-separated, of world, procs, rss"
    )
    try:
        print(json.dumps(asyncio.run(main(parser.parse_args()))))
    except KeyboardInterrupt:  # (its processes are ended on the way out)
        sys.exit("floors: interrupted")
