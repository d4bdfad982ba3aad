"""`mover router`: a generated mTLS + ACL config lets members talk and keeps others out."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

import pytest

from mover import Node, NodeConfig, TeamCredentials, Unreachable
from mover._config import _read_overrides, free_port
from mover.cli._router import generate_config

pytestmark = pytest.mark.processes


async def test_members_talk_through_a_secured_router_and_outsiders_cannot_connect(
    tmp_path: Path,
) -> None:
    port = free_port()
    generate_config(tmp_path, "alpha", ["a", "b"], "127.0.0.1", port)
    router = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "mover._cli",
        "router",
        "--config",
        str(tmp_path / "router.json"),
        stdout=asyncio.subprocess.PIPE,
    )
    try:
        assert router.stdout is not None
        line = await asyncio.wait_for(router.stdout.readline(), 20)
        assert line.startswith(b"router ")
        team = TeamCredentials.generate("alpha")

        def member(name: str) -> NodeConfig:
            return NodeConfig(
                mode="client",
                listen=(),
                overrides=_read_overrides(str(tmp_path / f"member-{name}.json")),
            )

        async with (
            Node("a", team, config=member("a")) as a,
            Node("b", team, config=member("b")) as b,
        ):
            b.export(lambda x: 2 * x, "double")
            await a.membership.wait_for({"a", "b"}, timeout=10)
            assert await a.call("b", "double", 21, timeout=5) == 42
        outsider = NodeConfig(
            mode="client", listen=(), connect=(f"tls/127.0.0.1:{port}",), patience=0.5
        )
        with pytest.raises(Unreachable):  # a tool gives up after its patience; a member waits
            async with Node("c", team, config=outsider, observer=True):
                pass
    finally:
        router.terminate()
        try:
            await asyncio.wait_for(router.wait(), 20)  # it closes within its own bound (10 s)
        except TimeoutError:
            router.kill()
            await router.wait()
            raise
