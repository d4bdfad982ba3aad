"""One team file across hosts: ``mover up TEAM.toml --host NAME`` on each of two hosts (a: the
router and the lock-step world; b: three robots), every link mutual TLS with the certificates
and ACL of ``mover up --gen-config``, and search and rescue run with ``mover run`` from a third
host with the workstation's certificate. Host b starts first: its ``mover up`` says it waits
for the router, and comes up when host a does."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from pathlib import Path

import pytest

from mover._procs import Child, stop
from mover.testing import Netlab
from tests.helpers.procs import ROOT
from tests.netlab import LAB

pytestmark = LAB

TEAM = """\
[team]
name = "rescue"
seed = 1
key_file = "team.key"
tls = "tls"

[[hosts]]
name = "a"
address = "{a}"

[[hosts]]
name = "b"
address = "{b}"

[world]
file = "{world}"
host = "a"
timeout = 5
record = true

[[robots]]
names = ["elvis", "ernst", "moseley"]
host = "b"
"""
LADDER = [(signal.SIGINT, 10.0), (signal.SIGTERM, 3.0), (signal.SIGKILL, 3.0)]


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MOVER_")}
    return env | {"PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"} | extra


class Up:
    """``mover up --host`` on one host of the lab: its lines, and when it said it is ready."""

    def __init__(self, child: Child) -> None:
        self.child = child
        self.lines: list[str] = []
        self.ready = asyncio.Event()
        self.pump = asyncio.ensure_future(child.pump(self.heard))

    def heard(self, line: str) -> None:
        self.lines.append(line)
        if line.startswith("[up] ready in "):
            self.ready.set()


@pytest.mark.timeout(300)
async def test_one_team_file_two_hosts_and_a_run_from_a_third(tmp_path: Path) -> None:
    async with Netlab(("a", "b", "c")) as lab:
        team = tmp_path / "team.toml"
        world = ROOT / "worlds" / "search_and_rescue.toml"
        team.write_text(TEAM.format(a=lab["a"].address, b=lab["b"].address, world=world))
        (tmp_path / "team.key").write_text(os.urandom(32).hex() + "\n")
        tls = str(tmp_path / "tls")
        code, said = await lab.run(
            "a", sys.executable, "-m", "mover._up", str(team), "--gen-config", tls, env=_env()
        )  # fmt: skip
        assert code == 0, said
        assert "member-up-b.json" in said and "member-workstation.json" in said

        ups: dict[str, Up] = {}
        try:
            for host in ("b", "a"):  # b first: it waits for a's router
                child = await lab.start(
                    host,
                    [sys.executable, "-m", "mover._up", str(team), "--host", host,
                     "--out", str(tmp_path / f"run-{host}")],
                    env=_env(), log=(tmp_path / f"up-{host}.log").open("ab"), pump=True,
                    label=f"up {host}",
                )  # fmt: skip
                ups[host] = Up(child)
                if host == "b":
                    await asyncio.sleep(6.0)  # long enough to say it waits
            async with asyncio.timeout(90):
                await asyncio.gather(*(u.ready.wait() for u in ups.values()))

            tool = tmp_path / "tls" / "member-workstation.json"
            env = _env(
                MOVER_TEAM="rescue", MOVER_TEAM_KEY_FILE=str(tmp_path / "team.key"),
                MOVER_MODE="client", MOVER_LISTEN="", MOVER_ZENOH_CONFIG=str(tool),
            )  # fmt: skip
            code, said = await lab.run(
                "c", sys.executable, "-m", "mover._cli", "run", "search_and_rescue",
                "--robots", "elvis,ernst,moseley", "--run-id", "rescue", "--wait", "60",
                env=env, timeout=150,
            )  # fmt: skip
            print(said)
            assert code == 0, said
            assert said.count(": done") == 3
        finally:
            await stop([u.child for u in ups.values()], LADDER)
            for u in ups.values():
                await asyncio.wait_for(u.pump, 10)
        for host, u in ups.items():
            print(f"--- mover up --host {host}\n" + "\n".join(u.lines))
        waited = [x for x in ups["b"].lines if "cannot reach" in x]
        assert waited and "--host a" in waited[0]
        for u in ups.values():
            assert u.child.proc.returncode == 0
            assert not [x for x in u.lines if "Traceback" in x]
        assert "join with MOVER_TEAM=rescue MOVER_MODE=client MOVER_ZENOH_CONFIG=" in "\n".join(
            ups["a"].lines
        )
    assert lab.leftovers() == []
