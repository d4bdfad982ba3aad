"""The per-member ACL of ``mover router --gen-config``, on loopback through a real router: only
``<name>``'s certificate serves ``<name>``'s keys; a leaked workstation (tool) certificate
calls but hears none of a member's calls, not even through a wildcard queryable; a member's
certificate cannot serve another member's keys. (Across hosts: test_acl_hosts.py.)"""

from __future__ import annotations

import asyncio
import contextlib
import sys
from collections import Counter
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
import zenoh

from mover import Node, NodeConfig, TeamCredentials
from mover._config import _read_overrides, free_port
from mover.cli._acl import team_acl
from mover.cli._router import generate_config
from tests.helpers.procs import terminate

pytestmark = pytest.mark.processes

CALLS = 20


def test_every_name_gets_a_policy_of_its_own_and_tools_one_that_excludes_members() -> None:
    acl = team_acl("t", ["elvis", "world"], ["workstation"])
    assert acl["default_permission"] == "deny"
    subjects = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}
    assert sorted(subjects.values()) == [["elvis"], ["workstation"], ["world"]]
    rules = {r["id"]: r for r in acl["rules"]}
    serving = [r for r in rules.values() if "declare_queryable" in r["messages"]]
    by_keys = {tuple(r["key_exprs"]): r["permission"] for r in serving}
    assert by_keys[("mover/t/rpc/elvis", "mover/t/hello/elvis")] == "allow"
    assert by_keys[("mover/t/rpc/*", "mover/t/hello/*")] == "allow"  # the tools' fresh names
    denied = [k for k, p in by_keys.items() if p == "deny"]
    assert denied == [("mover/t/rpc/elvis", "mover/t/hello/elvis", "mover/t/rpc/world",
                       "mover/t/hello/world")]  # fmt: skip
    for policy in acl["policies"]:
        assert all(r in rules for r in policy["rules"])


@contextlib.asynccontextmanager
async def router(config: Path) -> AsyncIterator[None]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover._cli", "router", "--config", str(config),
        stdout=asyncio.subprocess.PIPE,
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        line = await asyncio.wait_for(proc.stdout.readline(), 20)
        assert line.startswith(b"router "), line
        yield
    finally:
        await terminate(proc, 20)


def _config(tls: Path, cert: str) -> NodeConfig:
    overrides = _read_overrides(str(tls / f"member-{cert}.json"))
    return NodeConfig(mode="client", listen=(), overrides=overrides)


async def test_a_leaked_certificate_cannot_serve_a_members_keys(tmp_path: Path) -> None:
    generate_config(tmp_path, "alpha", ["a", "b"], "127.0.0.1", free_port(), ["workstation"])
    team = TeamCredentials.generate("alpha")
    heard: Counter[str] = Counter()  # "<certificate>: <key of a query or put it was sent>"

    def hear(cert: str) -> zenoh.handlers.Callback[Any]:
        return zenoh.handlers.Callback(lambda m: heard.update([f"{cert}: {m.key_expr}"]))

    async with router(tmp_path / "router.json"):
        # leaked certificates, held by an outsider without the team key: a tool's, and b's
        thieves = {c: zenoh.open(_config(tmp_path, c).to_zenoh()) for c in ("workstation", "b")}
        declared: list[object] = []  # held: a declaration dropped is undeclared
        try:
            for cert, s in thieves.items():
                for key in ("rpc/a", "hello/a", "rpc/*", "**"):
                    declared.append(s.declare_queryable(f"mover/alpha/{key}", hear(cert)))
                declared.append(s.declare_subscriber("mover/alpha/ctl/*", hear(cert)))
            async with (
                Node("a", team, config=_config(tmp_path, "a")) as a,
                Node("b", team, config=_config(tmp_path, "b")) as b,
                Node("run-1", team, kind="tool", config=_config(tmp_path, "workstation")) as w,
            ):
                a.export(asyncio.sleep, "nap")
                await b.membership.wait_for({"a", "b", "run-1"}, timeout=10)
                for _ in range(CALLS):
                    assert await b.call("a", "nap", 0, timeout=5) is None
                    assert await w.call("a", "nap", 0, timeout=5) is None  # tools call
                    assert await a.call("run-1", "mover.procedures", timeout=5)  # and serve
                cancelled = asyncio.ensure_future(w.call("a", "nap", 30, timeout=40))
                await asyncio.sleep(0.5)
                cancelled.cancel()  # a control message on a's key
                with contextlib.suppress(asyncio.CancelledError):
                    await cancelled
                await asyncio.sleep(0.5)
        finally:
            for s in thieves.values():
                s.close()
    print(dict(heard))
    on_members = {k: n for k, n in heard.items() if k.endswith(("/a", "/b"))}
    assert on_members == {}
    assert heard["workstation: mover/alpha/rpc/run-1"] >= CALLS  # a tool hears tools' calls
