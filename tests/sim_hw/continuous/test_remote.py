"""The remote backend: real OS processes over zenoh on 127.0.0.1 (multicast scouting off).

A world process (``mover world --lockstep``) and robot processes
(``python -m sim_hw.continuous._walker``) on free ports; the same walkers in
process must give the same trajectories, bit for bit.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys
from collections.abc import AsyncIterator
from pathlib import Path

import numpy as np
import pytest

from mover import Node, NodeConfig, TeamCredentials
from mover._cli import main
from mover._config import free_port
from sim_hw import World, WorldServer, in_process, load_world, read_recording
from sim_hw.continuous._walker import random_walk
from tests.helpers.procs import ROOT

pytestmark = [pytest.mark.processes, pytest.mark.timeout(90)]

WORLD = """
[generator]
kind = "random_obstacles"
size = [6.0, 6.0]
count = 6
seed = 1
"""
SPEC = {"sonar": {"noise": 0.02}, "odometry": {"trans_noise": 0.05}}


class Procs:
    """Processes of one test on one seed port; all killed at the end."""

    def __init__(self) -> None:
        self.team = TeamCredentials.generate("simtest")
        self.port = free_port()
        self.procs: list[asyncio.subprocess.Process] = []

    def env(self, listen: bool) -> dict[str, str]:
        env = dict(os.environ)
        env.update(self.team.env())
        env["MOVER_MODE"] = "peer"
        seed = f"tcp/127.0.0.1:{self.port}"
        env["MOVER_LISTEN"] = seed if listen else "tcp/127.0.0.1:0"
        env["MOVER_CONNECT"] = "" if listen else seed
        return env

    async def start(self, *args: str, world: bool = False) -> asyncio.subprocess.Process:
        proc = await asyncio.create_subprocess_exec(
            sys.executable,
            *args,
            env=self.env(listen=world),
            cwd=ROOT,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        self.procs.append(proc)
        return proc

    async def world(self, path: Path, *flags: str) -> asyncio.subprocess.Process:
        return await self.start(
            "-m",
            "mover._cli",
            "world",
            str(path),
            "--lockstep",
            "--quit-when-empty",
            "--state-rate",
            "0",
            *flags,
            world=True,
        )

    async def walker(
        self, robot: str, seed: int, ticks: int, out: Path
    ) -> asyncio.subprocess.Process:
        return await self.start(
            "-m",
            "sim_hw.continuous._walker",
            robot,
            "--seed",
            str(seed),
            "--ticks",
            str(ticks),
            "--spec",
            json.dumps(SPEC),
            "--out",
            str(out),
        )

    async def close(self) -> None:
        for proc in self.procs:
            if proc.returncode is None:
                proc.kill()
            await proc.communicate()  # reap it and close its pipes


@pytest.fixture
async def procs() -> AsyncIterator[Procs]:
    p = Procs()
    yield p
    await p.close()


async def _finish(proc: asyncio.subprocess.Process, limit: float = 60.0) -> tuple[int, str]:
    _, err = await asyncio.wait_for(proc.communicate(), limit)
    return proc.returncode or 0, err.decode()


async def _in_process(
    path: Path, seed: int, walkers: dict[str, int], ticks: int
) -> dict[str, list[list[float]]]:
    server = WorldServer(World(load_world(path), seed=seed), expect=len(walkers))

    async def walk(robot: str, rng_seed: int) -> list[list[float]]:
        hw = await in_process(server, robot, SPEC)
        return await random_walk(hw, np.random.default_rng(rng_seed), ticks)

    tracks = await asyncio.gather(*(walk(r, s) for r, s in walkers.items()))
    await server.door.aclose()
    return dict(zip(walkers, tracks, strict=True))


async def test_remote_and_in_process_give_the_same_trajectories(
    procs: Procs, tmp_path: Path
) -> None:
    path = tmp_path / "field.toml"
    path.write_text(WORLD)
    walkers, ticks = {"r0": 100, "r1": 101}, 80
    rec = tmp_path / "run.jsonl"
    world = await procs.world(path, "--expect", "2", "--seed", "5", "--record", str(rec))
    robots = [await procs.walker(r, s, ticks, tmp_path / f"{r}.json") for r, s in walkers.items()]
    for proc in robots:
        code, err = await _finish(proc)
        assert code == 0, err
    code, err = await _finish(world)
    assert code == 0, err
    remote = {r: json.loads((tmp_path / f"{r}.json").read_text()) for r in walkers}
    local = await _in_process(path, 5, walkers, ticks)
    assert len(remote["r0"]) == ticks
    assert remote == local
    _, recorded = read_recording(rec)
    assert recorded[-1]["robots"]["r1"][:3] == local["r1"][-1]
    assert main(["replay", str(rec), "--out", str(tmp_path / "run.png")]) == 0


async def test_the_world_streams_snapshots(procs: Procs, tmp_path: Path) -> None:
    path = tmp_path / "field.toml"
    path.write_text(WORLD)
    world = await procs.start(
        "-m",
        "mover._cli",
        "world",
        str(path),
        "--speed",
        "5",
        "--state-rate",
        "5",
        "--until",
        "30",
        world=True,
    )
    walker = await procs.walker("r0", 1, 50, tmp_path / "r0.json")
    config = NodeConfig(connect=(f"tcp/127.0.0.1:{procs.port}",))
    async with Node("watcher", team=procs.team, kind="test", config=config) as node:
        sub = node.subscribe("world/state")
        await node.membership.wait_for(["world"], timeout=20)
        msg = await sub.get(timeout=20)
        assert msg.sender == "world"
        assert set(msg.data) >= {"tick", "t", "robots", "boxes"}
        while not msg.data["robots"]:
            msg = await sub.get(timeout=20)
        assert list(msg.data["robots"]) == ["r0"]
    code, err = await _finish(walker)
    assert code == 0, err
    world.kill()


async def test_a_killed_robot_does_not_hang_the_world(procs: Procs, tmp_path: Path) -> None:
    path = tmp_path / "field.toml"
    path.write_text(WORLD)
    world = await procs.world(path, "--expect", "2", "--timeout", "1")
    steady = await procs.walker("steady", 1, 100, tmp_path / "steady.json")
    doomed = await procs.walker("doomed", 2, 10**6, tmp_path / "doomed.json")
    assert doomed.stdout is not None
    line = await asyncio.wait_for(doomed.stdout.readline(), 30)
    assert line.strip() == b"READY"
    await asyncio.sleep(0.5)
    doomed.send_signal(signal.SIGKILL)
    code, err = await _finish(steady)
    assert code == 0, err
    code, err = await _finish(world)
    assert code == 0, err
    assert "robot doomed" in err
    assert "dropped" in err
    assert len(json.loads((tmp_path / "steady.json").read_text())) == 100
