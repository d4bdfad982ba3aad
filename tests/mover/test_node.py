"""Node behaviour within one process: lifecycle, membership events, subscriptions.

Several nodes in one process still talk over real zenoh sessions on 127.0.0.1.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading

import pytest

from mover import MemberEvent, MoverError, Node, NodeClosed, NodeConfig, TeamCredentials
from mover._config import free_port


def configs() -> tuple[NodeConfig, NodeConfig]:
    port = free_port()
    return (
        NodeConfig(listen=(f"tcp/127.0.0.1:{port}",)),
        NodeConfig(connect=(f"tcp/127.0.0.1:{port}",)),
    )


async def test_clean_shutdown_leaves_no_threads() -> None:
    before = set(threading.enumerate())
    seed, peer = configs()
    team = TeamCredentials.generate("alpha")
    async with Node("a", team, config=seed) as a, Node("b", team, config=peer):
        await a.membership.wait_for({"a", "b"}, timeout=10)
    assert set(threading.enumerate()) - before == set()
    with pytest.raises(MoverError, match="not open"):
        await a.call("b", "x")


async def test_join_and_leave_events() -> None:
    seed, peer = configs()
    team = TeamCredentials.generate("alpha")
    async with Node("a", team, config=seed) as a:
        events: list[MemberEvent] = []

        async def watch() -> None:
            async for event in a.membership.events():
                events.append(event)

        watcher = asyncio.create_task(watch())
        async with Node("b", team, config=peer, kind="eye-bot"):
            await a.membership.wait_for({"b"}, timeout=10)
            info = a.membership.info("b")
            assert info is not None and info.kind == "eye-bot"
        await a.membership.wait_gone("b", timeout=5)
        await asyncio.sleep(0)
        watcher.cancel()
        assert [(e.kind, e.name) for e in events] == [("join", "b"), ("leave", "b")]


async def test_pending_call_fails_when_the_caller_closes() -> None:
    seed, peer = configs()
    team = TeamCredentials.generate("alpha")
    async with Node("a", team, config=seed) as a, Node("b", team, config=peer) as b:

        async def forever() -> None:
            await asyncio.Event().wait()

        b.export(forever)
        await a.membership.wait_for({"b"}, timeout=10)
        call = asyncio.create_task(a.call("b", "forever", timeout=None))
        await asyncio.sleep(0.2)
        await a.close()
        with pytest.raises(NodeClosed):
            await call
        async with asyncio.timeout(10):  # after the 1 s grace for a flapping link
            while b._server.tasks:  # the callee cancels the closed caller's call
                await asyncio.sleep(0.05)


async def test_subscription_iterates_and_closes() -> None:
    seed, peer = configs()
    team = TeamCredentials.generate("alpha")
    async with Node("a", team, config=seed) as a, Node("b", team, config=peer) as b:
        sub = b.subscribe("t/x")
        probe = b.subscribe("t/probe")  # declared after t/x: once a probe gets through, so will t/x
        await a.membership.wait_for({"b"}, timeout=10)
        async with asyncio.timeout(10):
            while True:
                await a.broadcast("t/probe", 0)
                with contextlib.suppress(TimeoutError):
                    await probe.get(timeout=0.1)
                    break
        probe.close()
        for i in range(3):
            await a.broadcast("t/x", i, reliable=True)
        got = [(await sub.get(timeout=5)).data for _ in range(3)]
        assert got == [0, 1, 2]
        sub.close()
        with pytest.raises(StopAsyncIteration):
            await sub.get(timeout=1)
        with pytest.raises(ValueError, match="bad topic"):
            b.subscribe("t/*")
