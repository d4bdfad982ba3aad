"""A node that cannot reach its router at start says so in one line and tries again: a member
until the router answers, a tool for its patience (then Unreachable, one line). On loopback,
no namespaces needed."""

from __future__ import annotations

import asyncio
import logging
import sys

import pytest

from mover import Node, NodeConfig, TeamCredentials, Unreachable
from mover._config import free_port
from mover._node import REACH_SAY
from tests.helpers.procs import ROOT

pytestmark = pytest.mark.processes  # the router of the last test


def client(port: int, patience: float = 10.0) -> NodeConfig:
    return NodeConfig(
        mode="client", listen=(), connect=(f"tcp/127.0.0.1:{port}",), patience=patience
    )


async def test_a_tool_gives_up_after_its_patience_in_one_line(
    caplog: pytest.LogCaptureFixture,
) -> None:
    team = TeamCredentials.generate("reach")
    loop = asyncio.get_running_loop()
    started = loop.time()
    with pytest.raises(Unreachable, match=r"cannot reach tcp/127.0.0.1:\d+ within 1 s"):
        async with Node("ps", team, config=client(free_port(), 1.0), observer=True):
            pass
    assert loop.time() - started < 3.0
    said = [r.getMessage() for r in caplog.records if "cannot reach" in r.getMessage()]
    assert len(said) == 1 and "trying again for 1 s" in said[0]


async def test_a_member_waits_for_its_router_and_comes_up_with_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, "mover.node")
    team = TeamCredentials.generate("reach")
    port = free_port()
    member = asyncio.ensure_future(Node("m", team, config=client(port, 1.0)).open())
    await asyncio.sleep(2.0)  # longer than its patience: a member waits all the same
    assert not member.done()
    router = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover._cli", "router", "--listen", f"tcp/127.0.0.1:{port}",
        cwd=ROOT, stdout=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.DEVNULL,
    )  # fmt: skip
    try:
        node = await asyncio.wait_for(member, 20)
        assert node.connected()
        await node.close()
    finally:
        router.terminate()
        await asyncio.wait_for(router.wait(), 20)
    said = [r.getMessage() for r in caplog.records if r.name == "mover.node"]
    assert len([s for s in said if "cannot reach" in s]) == 1
    assert "trying again until it answers" in said[0]
    assert any(s.startswith("m: reached tcp/127.0.0.1:") for s in said)


async def test_a_peer_alone_says_so_every_few_seconds_and_when_it_has_a_link(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A peer opens whether or not the peer it connects to answers: it says after REACH_SAY s
    that it has no link (naming the endpoint), and once the other peer is up that it has one."""
    caplog.set_level(logging.WARNING, "mover.node")
    team = TeamCredentials.generate("reach")
    where = f"tcp/127.0.0.1:{free_port()}"
    async with Node("p", team, config=NodeConfig(listen=(), connect=(where,))) as alone:
        await asyncio.sleep(REACH_SAY + 1.5)
        said = [r.getMessage() for r in caplog.records if r.name == "mover.node"]
        assert [s for s in said if s.startswith(f"p: no link to {where}")], said
        async with Node("q", team, config=NodeConfig(listen=(where,))):
            for _ in range(40):
                if alone.connected():
                    break
                await asyncio.sleep(0.25)
            await asyncio.sleep(1.5)  # the watch looks once a second
    said = [r.getMessage() for r in caplog.records if r.name == "mover.node"]
    assert any(s.startswith("p: linked again after") for s in said), said
