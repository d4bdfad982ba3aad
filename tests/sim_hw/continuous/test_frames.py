"""One exchange per tick: commands and readings as frames, over real zenoh sessions on 127.0.0.1.

The world and its robots are nodes in this process (the multi-process runs are in
test_remote.py); what is checked here is what goes over the wire.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from typing import Any

from mover import Node, NodeConfig, TeamCredentials
from mover._config import free_port
from sim_hw import World, WorldServer, in_process, random_obstacles, remote
from sim_hw._frames import topics as frame_topics
from sim_hw._process import serve


@contextlib.asynccontextmanager
async def _team(
    expect: int, *names: str, frames: bool = True, control_delay: int = 0
) -> AsyncIterator[list[Any]]:
    """A world node serving a fresh lock-step world, and member nodes ``names``, all joined."""
    port = free_port()
    seed = NodeConfig(listen=(f"tcp/127.0.0.1:{port}",))
    peer = NodeConfig(connect=(f"tcp/127.0.0.1:{port}",))
    team = TeamCredentials.generate("frames")
    arena = World(random_obstacles((6.0, 6.0), 0))
    server = WorldServer(arena, expect=expect, control_delay=control_delay)
    async with contextlib.AsyncExitStack() as stack:
        world = await stack.enter_async_context(Node("world", team, kind="world", config=seed))
        nodes = [await stack.enter_async_context(Node(n, team, config=peer)) for n in names]
        serve(world, server.door, frames=frames)
        await world.membership.wait_for({"world", *names}, timeout=10)
        yield [server, world, *nodes]


async def _ticks(hw: object, n: int) -> list[float]:
    out = []
    for _ in range(n):
        hw.drive.set_velocity(0.2, 0.3)  # type: ignore[attr-defined]
        await hw.clock.tick()  # type: ignore[attr-defined]
        out.append(hw.clock.now())  # type: ignore[attr-defined]
    return out


async def test_ticks_go_as_frames_after_the_first() -> None:
    async with _team(2, "a", "b") as (_, world, a, b):
        ha, hb = await asyncio.gather(remote(a, "a"), remote(b, "b"))
        times = await asyncio.wait_for(asyncio.gather(_ticks(ha, 20), _ticks(hb, 20)), 30)
        assert times[0] == times[1] and len(set(times[0])) == 20  # in lock-step, tick by tick
        # join and the first tick are calls; the 19 other ticks are one frame each way
        assert a.stats["sent.call"] == 2 and b.stats["sent.call"] == 2
        assert world.stats["recv.bc"] == 38
        assert world.stats["sent.bc_frames"] == 19  # one frame of readings per tick, for both


async def _steer(hw: Any, n: int) -> list[float]:
    """Drive by the sonar for ``n`` ticks (what a robot does depends on what it read)."""
    out = []
    for _ in range(n):
        near = min(hw.sonar.ranges())
        hw.drive.set_velocity(0.4 if near > 0.5 else 0.0, 0.0 if near > 0.5 else 1.0)
        await hw.clock.tick()
        out.append(round(hw.clock.now() / 0.1))
    return out


async def test_with_a_control_delay_robots_read_every_tick_from_frames_the_world_ahead() -> None:
    seen: list[Any] = []
    async with _team(2, "a", "b", control_delay=2) as (server, _, a, b):
        server.door.on_tick.append(lambda _: seen.append(server.world.snapshot()))
        ha, hb = await asyncio.gather(remote(a, "a"), remote(b, "b"))
        ticks = await asyncio.wait_for(asyncio.gather(_steer(ha, 30), _steer(hb, 30)), 30)
        assert ticks[0] == ticks[1] == list(range(1, 31))  # every tick's readings, in order
        assert a.stats["sent.call"] == 2 and b.stats["sent.call"] == 2  # no frame was missing
        assert 30 <= server.world.tick <= 32  # up to two ticks ahead (32 once C(29) is in)
    # the same run in one process: the same world, tick by tick
    here = WorldServer(World(random_obstacles((6.0, 6.0), 0)), expect=2, control_delay=2)
    again: list[Any] = []
    here.door.on_tick.append(lambda _: again.append(here.world.snapshot()))
    ia, ib = await asyncio.gather(in_process(here, "a"), in_process(here, "b"))
    await asyncio.wait_for(asyncio.gather(_steer(ia, 30), _steer(ib, 30)), 30)
    await here.door.aclose()
    assert len(again) == 32 and again[: len(seen)] == seen


async def test_a_command_frame_only_counts_from_its_robot() -> None:
    async with _team(1, "a", "mallory") as (server, _, a, mallory):
        ha = await remote(a, "a")
        await ha.clock.tick()  # the first tick, by call
        commands, _ = frame_topics("world")
        # a member that speaks for another robot is not believed: the tick does not happen
        mallory.broadcast_nowait(commands, ["a", 1, {"v": 1.0, "w": 0.0}], reliable=True)
        mallory.broadcast_nowait(commands, ["a", "1", "junk"], reliable=True)
        await asyncio.sleep(0.3)
        assert server.world.tick == 1
        assert server.world.robots["a"].v == 0.0
        await asyncio.wait_for(_ticks(ha, 3), 10)
        assert server.world.tick == 4


async def test_without_frames_every_tick_is_a_call() -> None:
    async with _team(1, "a", frames=False) as (_, world, a):
        ha = await remote(a, "a")
        await asyncio.wait_for(_ticks(ha, 5), 10)
        assert a.stats["sent.call"] == 6 and world.stats["recv.bc"] == 0


async def test_an_idle_robot_holds_nothing_back_and_reads_the_frames() -> None:
    async with _team(2, "a", "b") as (server, world, a, b):
        ha, hb = await asyncio.gather(remote(a, "a"), remote(b, "b"))
        await asyncio.wait_for(asyncio.gather(_ticks(ha, 2), _ticks(hb, 2)), 30)
        async with hb.clock.idling():
            assert (await world.call("world", "status", timeout=5))["idle"] == ["b"]
            times = await asyncio.wait_for(_ticks(ha, 10), 30)
            async with asyncio.timeout(5):  # the last frame's entry for b is on its way
                while hb.clock.now() < times[-1]:
                    await asyncio.sleep(0.01)
            assert server.world.robots["b"].v == 0.0  # stopped while idle
        assert (await world.call("world", "status", timeout=5))["idle"] == []
        await asyncio.wait_for(asyncio.gather(_ticks(ha, 3), _ticks(hb, 3)), 30)
        assert server.world.tick == 15 and ha.clock.now() == hb.clock.now()
        # b's calls: its join, its first tick, idle and wake; every other tick was a frame
        assert b.stats["sent.call"] == 4


async def test_a_call_the_world_answers_late_is_asked_again() -> None:
    async with _team(2, "a", "b", frames=False) as (server, _, a, b):
        ha, hb = await asyncio.gather(remote(a, "a", call_timeout=0.3), remote(b, "b"))
        ticking = asyncio.ensure_future(_ticks(ha, 1))  # waits on b, longer than 0.3 s
        await asyncio.sleep(1.0)
        assert not ticking.done() and server.door.dropped == []
        await _ticks(hb, 1)
        assert len(await asyncio.wait_for(ticking, 5)) == 1
        assert a.stats["sent.call"] >= 4  # its join, then the step asked three times or more
