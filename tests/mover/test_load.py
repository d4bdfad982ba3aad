"""Load tolerance: the membership timeouts are settings (NodeConfig fields and MOVER_* variables,
bounded where they are read), and a small team under a call load sees no member leave.

The 50-member figures are ``bench/team.py``'s (docs/transport.md); this runs its load at a size
the shared test machine can afford.
"""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from pathlib import Path

import pytest

from mover import ConfigError, Node, NodeConfig, TeamCredentials
from mover._config import free_port

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]


def test_the_timeouts_are_read_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    for var, value in [
        ("MOVER_LEASE_MS", "3000"),
        ("MOVER_KEEP_ALIVE", "6"),
        ("MOVER_HELLO_TIMEOUT", "2.5"),
        ("MOVER_HELLO_RETRIES", "3"),
        ("MOVER_LEAVE_GRACE", "0"),
    ]:
        monkeypatch.setenv(var, value)
    config = NodeConfig.from_env()
    assert (config.lease_ms, config.keep_alive) == (3000, 6)
    assert (config.hello_timeout, config.hello_retries, config.leave_grace) == (2.5, 3, 0.0)
    env = config.env()  # a child started with these settings gets them
    assert env["MOVER_LEASE_MS"] == "3000" and env["MOVER_LEAVE_GRACE"] == "0.0"
    assert "MOVER_LEASE_MS" not in NodeConfig().env()  # defaults leave a parent's value be
    assert config.to_zenoh() is not None


@pytest.mark.parametrize(
    ("var", "value", "said"),
    [
        ("MOVER_LEASE_MS", "soon", r"\$MOVER_LEASE_MS must be an integer"),
        ("MOVER_LEASE_MS", "1.5", r"\$MOVER_LEASE_MS must be an integer"),
        ("MOVER_LEASE_MS", "5", r"\$MOVER_LEASE_MS must be from 100"),
        ("MOVER_LEASE_MS", "99999999999", r"\$MOVER_LEASE_MS must be from"),
        ("MOVER_KEEP_ALIVE", "0", r"\$MOVER_KEEP_ALIVE must be from 1"),
        ("MOVER_HELLO_TIMEOUT", "nan", r"\$MOVER_HELLO_TIMEOUT must be from"),
        ("MOVER_HELLO_TIMEOUT", "inf", r"\$MOVER_HELLO_TIMEOUT must be from"),
        ("MOVER_HELLO_TIMEOUT", "-1", r"\$MOVER_HELLO_TIMEOUT must be from"),
        ("MOVER_HELLO_RETRIES", "1e9", r"\$MOVER_HELLO_RETRIES must be an integer"),
        ("MOVER_LEAVE_GRACE", "-0.5", r"\$MOVER_LEAVE_GRACE must be from"),
    ],
)
def test_a_bad_timeout_in_the_environment_is_refused(
    monkeypatch: pytest.MonkeyPatch, var: str, value: str, said: str
) -> None:
    monkeypatch.setenv(var, value)
    with pytest.raises(ConfigError, match=said):
        NodeConfig.from_env()


@pytest.mark.parametrize(
    "fields",
    [
        {"lease_ms": 0},
        {"lease_ms": 1000.5},
        {"lease_ms": True},
        {"keep_alive": 1000},
        {"lease_ms": 100, "keep_alive": 20},  # a keep-alive every 5 ms
        {"hello_timeout": float("nan")},
        {"hello_retries": -1},
        {"leave_grace": float("inf")},
    ],
)
def test_a_bad_timeout_field_is_refused(fields: dict[str, object]) -> None:
    with pytest.raises(ConfigError, match="must be"):
        NodeConfig(**fields)  # type: ignore[arg-type]


async def test_the_node_uses_its_hello_and_grace_settings() -> None:
    """A hello question waits hello_timeout; what a member held is given up after leave_grace."""
    team, port = TeamCredentials.generate("alpha"), free_port()
    fast = {"hello_timeout": 0.5, "hello_retries": 1, "leave_grace": 0.0}
    seed = NodeConfig(listen=(f"tcp/127.0.0.1:{port}",), **fast)  # type: ignore[arg-type]
    async with Node("a", team, config=seed) as a:
        gone: list[str] = []
        a.membership.on_gone(gone.append)
        async with Node("b", team, config=NodeConfig(connect=(f"tcp/127.0.0.1:{port}",))):
            await a.membership.wait_for({"b"}, timeout=10)
        await a.membership.wait_gone("b", timeout=5)
        assert await a.membership.verify("nobody", timeout=2.0) is None
        for _ in range(50):  # leave_grace 0: given up on the next turns of the loop
            if gone:
                break
            await asyncio.sleep(0.01)
        assert gone == ["b"]


@pytest.mark.timeout(90)
def test_ten_members_under_call_load_lose_no_reply_and_see_no_flap() -> None:
    """bench/team.py's load part at 10 members for 5 s: every call answered, nobody left."""
    proc = subprocess.run(
        [sys.executable, "bench/team.py", "--members", "10", "--seconds", "5", "--parts", "load"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=80,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    figures = json.loads(proc.stdout.splitlines()[-1])
    assert figures["load_topology_10"] == "peer"  # mover up's rule for 10 members
    assert figures["load_calls_per_s_10"] > 10
    assert (figures["lost_replies_10"], figures["member_flaps_10"]) == (0, 0), proc.stdout
