"""A leaked workstation certificate without the team key, across hosts: the outsider (host d)
connects to the router with it and declares queryables and a subscriber on a robot's keys
(exactly and by wildcard); the router never hands it a robot's call or control message, and
search and rescue completes (hosts a: router and world, b: robots, c: ``mover run``)."""

from __future__ import annotations

import asyncio
import json
import re
import signal
import sys
from pathlib import Path

import pytest

from mover._netteam import losses
from mover._up import load_team
from mover.testing import Netlab, TeamAcrossHosts
from tests.helpers.procs import ROOT
from tests.netlab import LAB

pytestmark = LAB

OUTSIDER = r"""
import json, sys, time, zenoh
conf = zenoh.Config()
for key, value in json.load(open(sys.argv[1])).items():
    conf.insert_json5(key, json.dumps(value))
heard = {}
def hear(what):
    def count(m):
        key = f"{what} {m.key_expr}"
        heard[key] = heard.get(key, 0) + 1
    return count
with zenoh.open(conf) as s:
    held = [s.declare_queryable(f"mover/rescue/{k}", hear("query"))
            for k in ("rpc/elvis", "hello/elvis", "rpc/*", "hello/*", "**")]
    held.append(s.declare_subscriber("mover/rescue/ctl/*", hear("put")))
    tokens = []
    held.append(s.liveliness().declare_subscriber(
        "mover/rescue/alive/*", lambda t: tokens.append(str(t.key_expr)), history=True))
    print("OUTSIDER up", flush=True)
    try:
        while True:
            time.sleep(0.5)
            print("HEARD", json.dumps(heard), "TOKENS", len(tokens), flush=True)
    except KeyboardInterrupt:
        pass
"""


@pytest.mark.timeout(300)
async def test_a_leaked_workstation_certificate_serves_no_robot_and_the_run_completes(
    tmp_path: Path,
) -> None:
    plan = load_team(ROOT / "teams" / "search_and_rescue.toml")
    lines: list[str] = []
    async with (
        Netlab(("a", "b", "c", "d")) as lab,
        TeamAcrossHosts(lab, plan, out=tmp_path, seed=1) as team,
    ):
        leaked = tmp_path / "tls" / "member-workstation.json"
        outsider = await lab.start(
            "d", [sys.executable, "-c", OUTSIDER, str(leaked)],
            log=(tmp_path / "outsider.log").open("ab"), pump=True, label="outsider",
        )  # fmt: skip
        pump = asyncio.ensure_future(outsider.pump(lines.append))
        result = await team.run_program(timeout=150)
        lost = losses(result, team)
        outsider.signal(signal.SIGINT)
        await asyncio.wait_for(pump, 10)
    print(result.text)
    print("\n".join(lines[-2:]))
    assert result.code == 0
    assert result.text.count(": done") == 3
    assert lost == {}
    said = [m for x in lines if (m := re.fullmatch(r"HEARD (\{.*\}) TOKENS (\d+)", x))]
    assert said, lines[-3:]
    heard, tokens = json.loads(said[-1].group(1)), int(said[-1].group(2))
    assert tokens >= 4  # connected, and it sees who is there (liveliness is not secret)
    members = ("elvis", "ernst", "moseley", "world")
    assert [k for k in heard if k.endswith(members)] == [], heard
