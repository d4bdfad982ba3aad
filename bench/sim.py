"""Simulated seconds per wall second of the continuous world in lock-step.

    python bench/sim.py [--quick] [--no-procs] [--procs 10,50] [--other-topology]

(a) the world alone: 10, 50, 200, 1000 in-process robots (8 sonar rays at 10 Hz, no camera, a
trivial bounce-off-walls controller) through the lock-step WorldServer and the in-process HAL,
where the world places them (rows 0.6 m apart from the bottom-left corner: a crowd, whatever
the arena's size); and 1000 again spread over the arena on a square lattice (its density,
about 4 m² a robot) as ``rtf_world_1000_spread``;
(b) 10 and 50 robot processes (``python -m sim_hw.continuous._walker``) driving a random walk
through the remote HAL over zenoh on 127.0.0.1, the world hosted in this process, in the
topology ``mover up`` picks for a team of that size (``mover._up.needs_router``: the walkers and
the world as peers of one mesh, or all of them clients of one ``mover router`` process). Time
is counted from the first tick to the last, so process start-up is left out.

Each process figure is also given as a ratio against the world alone at the same size, from
the same run: ``procs_efficiency_N = rtf_procs_N / rtf_world_N`` (what the processes and the
network cost). The same 10 processes also run once with one call per tick instead of frames
(the exchange before frames), as ``rtf_procs_10_calls`` and ``frames_speedup_10``.

``--other-topology`` also runs each process figure in the other topology
(``rtf_procs_N_other``, and ``topology_gain_N = rtf_procs_N / rtf_procs_N_other``).

The last line is one JSON object: rtf_world_10, rtf_world_50, rtf_world_200, rtf_world_1000,
rtf_world_1000_spread,
rtf_procs_10,
rtf_procs_50, procs_topology_10, procs_topology_50, procs_efficiency_10, procs_efficiency_50,
rtf_procs_10_calls, frames_speedup_10 (null where not measured), and with --other-topology
rtf_procs_10_other, rtf_procs_50_other, topology_gain_10, topology_gain_50.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import os
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mover import Node, NodeConfig, TeamCredentials  # noqa: E402
from mover._config import free_port  # noqa: E402
from mover._up import needs_router  # noqa: E402  # the topology rule of `mover up`
from sim_hw import World, WorldServer, WorldSpec, in_process  # noqa: E402
from sim_hw._process import serve  # noqa: E402

ROBOT = {"sonar": {"rays": 8, "max_range": 3.0}, "camera": False}


def _arena(n: int) -> WorldSpec:
    side = max(6.0, math.sqrt(n * 4.0))  # ~4 m² a robot
    return WorldSpec(size=(side, side), name=f"bench-{n}")


class _Timer:
    """A hook on a door's ``on_tick``: wall time of ``world``'s first and last tick."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.first: float | None = None
        self.first_t = 0.0
        self.last = 0.0
        self.last_t = 0.0

    def __call__(self, commands: Mapping[str, Mapping[str, Any]]) -> None:
        now, world = time.perf_counter(), self.world
        if self.first is None:
            self.first, self.first_t = now, world.time
        self.last, self.last_t = now, world.time

    def rtf(self) -> float:
        assert self.first is not None
        return (self.last_t - self.first_t) / max(self.last - self.first, 1e-9)


async def world_alone(n: int, seconds: float, *, spread: bool = False) -> float:
    """Real-time factor of n in-process robots for ``seconds`` simulated (``spread``: on a
    square lattice over the whole arena, else where the world places them)."""
    arena = _arena(n)
    gap = arena.size[0] / math.ceil(math.sqrt(n))
    server = WorldServer(World(arena, seed=1), expect=n)
    timer = _Timer(server.world)
    server.door.on_tick.append(timer)
    ticks = round(seconds / 0.1)

    async def robot(i: int) -> None:
        spec = dict(ROBOT)
        if spread:
            row, col = divmod(i, math.ceil(math.sqrt(n)))
            spec["pose"] = [gap * (col + 0.5), gap * (row + 0.5), 0.0]
        hw = await in_process(server, f"r{i:03d}", spec)
        turn = 1.0 if i % 2 else -1.0
        assert hw.sonar is not None
        for _ in range(ticks):
            ahead = min(hw.sonar.ranges()[0:2])
            hw.drive.set_velocity(0.0 if ahead < 0.3 else 0.4, turn if ahead < 0.3 else 0.0)
            await hw.clock.tick()

    await asyncio.gather(*(robot(i) for i in range(n)))
    await server.door.aclose()
    return timer.rtf()


async def processes(n: int, seconds: float, *, frames: bool = True, router: bool) -> float:
    """Real-time factor of n walker processes on the remote HAL (``router``: every process,
    the world's included, a client of one router process; else a peer mesh)."""
    team, port = TeamCredentials.generate("bench"), free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    server = WorldServer(World(_arena(n), seed=1), expect=n, timeout=10.0)
    timer = _Timer(server.world)
    server.door.on_tick.append(timer)
    if router:
        config = theirs = NodeConfig(mode="client", listen=(), connect=(endpoint,))
    else:
        config, theirs = NodeConfig(listen=(endpoint,)), NodeConfig(connect=(endpoint,))
    env = dict(os.environ, **team.env(), **theirs.env())
    ticks = round(seconds / 0.1)
    hub = None
    if router:
        hub = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "mover", "router", "--listen", endpoint,
            env=env, cwd=ROOT, stdout=asyncio.subprocess.PIPE,
        )  # fmt: skip
        assert hub.stdout is not None
        await asyncio.wait_for(hub.stdout.readline(), 30)  # it listens
    try:
        return await _walk(n, ticks, frames, team, config, env, server, timer)
    finally:
        if hub is not None:
            hub.kill()
            await hub.wait()


async def _walk(
    n: int,
    ticks: int,
    frames: bool,
    team: TeamCredentials,
    config: NodeConfig,
    env: dict[str, str],
    server: WorldServer,
    timer: _Timer,
) -> float:
    async with Node("world", team=team, kind="world", config=config) as node:
        serve(node, server.door, frames=frames)
        procs = [
            await asyncio.create_subprocess_exec(
                sys.executable,
                "-m",
                "sim_hw.continuous._walker",
                f"r{i:03d}",
                "--seed",
                str(i),
                "--ticks",
                str(ticks),
                "--spec",
                json.dumps({"camera": False}),
                "--timeout",
                "60",
                env=env,
                cwd=ROOT,
                stdout=asyncio.subprocess.DEVNULL,
                stderr=asyncio.subprocess.PIPE,
            )
            for i in range(n)
        ]
        try:
            results = await asyncio.wait_for(
                asyncio.gather(*(p.communicate() for p in procs)), timeout=120 + 2 * n
            )
        finally:
            for p in procs:
                if p.returncode is None:
                    p.kill()
        failed = [p.returncode for p in procs if p.returncode]
        if failed:
            raise RuntimeError(f"{len(failed)} walkers failed: {results[0][1].decode()[-500:]}")
        await server.door.aclose()
    return timer.rtf()


async def main(args: argparse.Namespace) -> dict[str, Any]:
    scale = 0.3 if args.quick else 1.0
    out: dict[str, Any] = {}
    world: dict[int, float] = {}
    for n, seconds in ((10, 60.0), (50, 30.0), (200, 10.0), (1000, 5.0)):
        rtf = world[n] = await world_alone(n, seconds * scale)
        out[f"rtf_world_{n}"] = round(rtf, 1)
        print(f"world alone, {n:3d} robots: {rtf:7.1f}x real time", flush=True)
    rtf = await world_alone(1000, 5.0 * scale, spread=True)
    out["rtf_world_1000_spread"] = round(rtf, 1)
    print(f"world alone, 1000 robots spread over the arena: {rtf:7.1f}x real time", flush=True)
    sizes = {int(x) for x in args.procs.split(",")}
    for n, seconds in ((10, 30.0), (50, 10.0)):
        key = f"rtf_procs_{n}"
        if n not in sizes:  # not asked for
            out[key] = out[f"procs_efficiency_{n}"] = None
            continue
        router = needs_router(n + 1)  # the walkers and the world
        out[f"procs_topology_{n}"] = "router" if router else "peer"
        if args.no_procs:
            out[key] = out[f"procs_efficiency_{n}"] = None
            print(f"{n} robot processes: not measured (--no-procs)")
            continue
        rtf = await processes(n, seconds * scale, router=router)
        out[key] = round(rtf, 1)
        eff = rtf / world[n]
        out[f"procs_efficiency_{n}"] = round(eff, 3)
        print(
            f"{n:3d} robot processes ({out[f'procs_topology_{n}']}): {rtf:7.1f}x real time "
            f"({eff:.3f} of the world alone)",
            flush=True,
        )
        if args.other_topology:
            other = await processes(n, seconds * scale, router=not router)
            out[f"rtf_procs_{n}_other"] = round(other, 1)
            out[f"topology_gain_{n}"] = round(rtf / other, 2)
            print(f"{n:3d} robot processes, the other topology: {other:7.1f}x real time")
    out["rtf_procs_10_calls"] = out["frames_speedup_10"] = None
    if not args.no_procs and 10 in sizes:
        calls = await processes(10, 30.0 * scale, frames=False, router=needs_router(11))
        out["rtf_procs_10_calls"] = round(calls, 1)
        assert out["rtf_procs_10"] is not None
        out["frames_speedup_10"] = round(float(out["rtf_procs_10"]) / calls, 2)
        print(f" 10 robot processes, a call per tick: {calls:7.1f}x real time", flush=True)
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="30 %% of the simulated durations")
    parser.add_argument("--no-procs", action="store_true", help="skip the multi-process runs")
    parser.add_argument(
        "--procs", default="10,50", help="process counts to run: 10, 50 or both (default)"
    )
    parser.add_argument(
        "--other-topology",
        action="store_true",
        help="also run each process figure in the topology mover up does not pick",
    )
    result = asyncio.run(main(parser.parse_args()))
    print(json.dumps(result))
