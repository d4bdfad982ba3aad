"""A leaked workstation certificate without the team key, across hosts: the outsider (host d)
connects to the router with it and declares queryables and a subscriber on a robot's keys
(exactly and by wildcard), answering every query it gets; the router never hands it a robot's
call or control message, so a member asking ``rpc/elvis`` and ``hello/elvis`` never gets its
answer, and search and rescue completes (hosts a: router and world, b: robots, c: ``mover
run`` and the member's probe)."""

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
        if what == "query":
            m.reply(m.key_expr, b"OUTSIDER")  # denied by the ACL, were it ever asked
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

PROBE = r"""
import json, sys, time, zenoh
conf = zenoh.Config()
for key, value in json.load(open(sys.argv[1])).items():
    conf.insert_json5(key, json.dumps(value))
got = {}
with zenoh.open(conf) as s:
    for _ in range(int(sys.argv[2])):
        for key in ("rpc/elvis", "hello/elvis"):
            for r in s.get(f"mover/rescue/{key}", payload=b"probe", timeout=2.0,
                           target=zenoh.QueryTarget.ALL,
                           consolidation=zenoh.ConsolidationMode.NONE):
                if r.ok is not None:
                    data = bytes(r.ok.payload.to_bytes())
                    said = "OUTSIDER" if data == b"OUTSIDER" else data[:2].decode("latin-1")
                    got[f"{key} {said}"] = got.get(f"{key} {said}", 0) + 1
        time.sleep(0.25)
print("ANSWERS", json.dumps(got), flush=True)
"""
ROUNDS = 20  # of the probe's two queries


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
        async with asyncio.timeout(30):
            while "OUTSIDER up" not in lines:
                await asyncio.sleep(0.1)
        member = tmp_path / "tls" / "member-ernst.json"  # a member asking another
        probe = await lab.start(
            "c", [sys.executable, "-c", PROBE, str(member), str(ROUNDS)],
            log=(tmp_path / "probe.log").open("ab"), pump=True, label="probe",
        )  # fmt: skip
        probed: list[str] = []
        asked = asyncio.ensure_future(probe.pump(probed.append))
        result = await team.run_program(timeout=150)
        lost = losses(result, team)
        await asyncio.wait_for(asked, 60)
        outsider.signal(signal.SIGINT)
        done, _ = await asyncio.wait([pump], timeout=10)
        if not done:  # its zenoh session's close once hung past 10 s: what it heard is kept
            outsider.signal(signal.SIGKILL)
            await asyncio.wait_for(pump, 10)
    print(result.text)
    print("\n".join(lines[-2:] + probed[-1:]))
    assert result.code == 0
    assert result.text.count(": done") == 3
    assert lost == {}
    said = [m for x in lines if (m := re.fullmatch(r"HEARD (\{.*\}) TOKENS (\d+)", x))]
    assert said, lines[-3:]
    heard, tokens = json.loads(said[-1].group(1)), int(said[-1].group(2))
    assert tokens >= 4  # connected, and it sees who is there (liveliness is not secret)
    members = ("elvis", "ernst", "moseley", "world")
    assert [k for k in heard if k.endswith(members)] == [], heard
    answers = [json.loads(x[len("ANSWERS ") :]) for x in probed if x.startswith("ANSWERS ")]
    assert answers, probed[-3:]
    got = answers[-1]
    assert got.get("hello/elvis M2", 0) >= ROUNDS // 2, got  # elvis answered the member
    assert [k for k in got if k.endswith("OUTSIDER")] == [], got  # the outsider never did
