"""Search and rescue across hosts, on a clean and a bad network (issue 23's figures).

    sudo python bench/network.py [--scenario all|clean|rtt100|partition|stall|loss2|loss10]
                                 [--seed 1] [--control-delay 2] [--out DIR] [--timeout 120]
                                 [--loss-timeout 360] [--patience S]

Builds three hosts (network namespaces, :mod:`mover._netlab`): a runs ``mover router`` (mutual
TLS and the ACL of ``mover router --gen-config``) and the lock-step world, b the three robots,
joining through an impairment proxy in a (:mod:`mover._impair`), c the workstation's ``mover
run`` (:mod:`mover._netteam`). Each scenario is one run of ``teams/search_and_rescue.toml``
with the world's control delay of teams across hosts, ``--control-delay`` ticks (default
``CONTROL_DELAY``, 2: a command for tick t applies at t + 2, ``sim_hw._delayed``):

- ``clean``: nothing impaired.
- ``rtt100``: 50 ms each way on b's links (a 100 ms round trip); stopped after ``--rtt-for`` s.
- ``partition``: b's cable pulled for 5 s, 0.5 s into the run.
- ``stall``: the router SIGSTOPped for 5 s, 0.5 s into the run.
- ``loss2``, ``loss10``: b's links 50 ± 20 ms each way with 2 % (10 %) of chunks a
  retransmission (200 ms, doubling) late; given ``--loss-timeout`` s to complete.

Each run prints one line (its outcome); the last line is one JSON object with what can be
measured so far: ``control_delay``, ``rtf_lockstep_clean`` and ``rtf_lockstep_rtt100``
(simulated seconds per wall second of the run), ``partition_5s_added_s`` (seconds the
partition added to the clean run; null when the run failed), ``spurious_member_lost_loss10``
(members said to be lost under loss: none died) and ``loss10_run_s``, ``tracebacks`` (in all
processes of all runs), ``recordings_identical`` (the recordings of the runs not stopped early
-- clean, partition, stall, loss2, loss10 -- are byte for byte the clean run's: the same
control delay and seed give one run whatever the network did; ``recordings_differ`` names
those that are not, or did not complete), and per scenario ``code`` (``mover run``'s exit;
null: stopped at the time allowed), ``run_s``, ``sim_s`` (the last tick recorded), ``rtf``,
``recording_sha256``, ``losses`` (lines telling of a lost member or world, per process),
``lost_members`` and ``tracebacks`` per process. Needs root and
``ip netns``; leaves no namespace or process.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from mover._config import NodeConfig
from mover._impair import Impairment
from mover._netlab import Netlab, unavailable
from mover._netteam import TeamAcrossHosts, last_tick, losses, lost_members
from mover._up import load_team

ROOT = Path(__file__).resolve().parents[1]
TEAM_FILE = ROOT / "teams" / "search_and_rescue.toml"
SCENARIOS = ("clean", "rtt100", "partition", "stall", "loss2", "loss10")
COMPARED = ("partition", "stall", "loss2", "loss10")
"""The scenarios whose recording must be the clean run's (rtt100 is stopped early)."""
LOSS = {"loss2": 0.02, "loss10": 0.1}
CONTROL_DELAY = 2
"""Ticks of control delay for a team across hosts: rtf 2.7 at a 100 ms round trip where
K = 0 gives 0.94 and K = 1 1.9 (results/network/README.md)."""
FAULT_AT = 0.5
"""Seconds into the run a partition or a stall begins (the clean run takes ~1.5 s at K = 2)."""
FAULT_FOR = 5.0


async def scenario(
    name: str,
    out: Path,
    seed: int,
    timeout: float,
    rtt_for: float,
    patience: float | None,
    control_delay: int = CONTROL_DELAY,
) -> dict[str, Any]:
    """Run one scenario; its figures."""
    plan = load_team(TEAM_FILE)
    if patience is not None:
        plan = replace(plan, patience=patience)
    if control_delay and plan.world is not None:  # the world's control delay (sim_hw._delayed)
        plan = replace(plan, world=replace(plan.world, control_delay=control_delay))
    t0 = time.monotonic()
    async with (
        Netlab(("a", "b", "c")) as lab,
        TeamAcrossHosts(lab, plan, out=out, seed=seed) as team,
    ):
        up_s = time.monotonic() - t0
        proxy = team.proxy
        assert proxy is not None
        if name == "rtt100":
            proxy.up = proxy.down = Impairment(0.05)
            timeout = rtt_for
        elif name in LOSS:
            proxy.up = proxy.down = Impairment(0.05, 0.02, loss=LOSS[name])
        fault = name if name in ("partition", "stall") else None
        result = await team.run_with_fault(fault, at=FAULT_AT, seconds=FAULT_FOR, timeout=timeout)
        # read before the team stops (a stop makes members leave, and the world says so)
        figures: dict[str, Any] = {
            "code": result.code,
            "up_s": round(up_s, 1),
            "run_s": None if result.run_s is None else round(result.run_s, 1),
            "losses": losses(result, team),
            "lost_members": sorted(lost_members(result, team)),
            "proxy": {
                "connections": proxy.stats.connections,
                "chunks": proxy.stats.chunks,
                "lost_chunks": proxy.stats.lost,
                "max_hold_s": round(proxy.stats.max_hold, 2),
            },
        }
    # the team is stopped: the recording is complete
    sim = last_tick(team.recording)
    figures["sim_s"] = None if sim is None else round(sim, 2)
    figures["rtf"] = rtf(figures)
    if team.recording.exists():
        figures["recording_sha256"] = hashlib.sha256(team.recording.read_bytes()).hexdigest()
    figures["tracebacks"] = team.tracebacks()
    if result.fault:
        figures["fault"] = result.fault
    waits = [line for _, line in result.lines if "waiting for" in line or "answering again" in line]
    if waits:
        figures["waited"] = waits[:4]
    failed = [line for _, line in result.lines if "FAILED" in line or "mover run:" in line]
    figures["said"] = failed[:4]
    return figures


def rtf(s: dict[str, Any]) -> float | None:
    """Simulated seconds per wall second of a scenario's run."""
    if not s.get("sim_s") or not s.get("run_s"):
        return None
    return round(float(s["sim_s"]) / float(s["run_s"]), 2)


def same_recordings(found: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Whether the recordings of the runs compared are the clean run's (with ``clean`` and at
    least one other run)."""
    runs = [n for n in COMPARED if n in found]
    if "clean" not in found or not runs:
        return {}
    clean = found["clean"].get("recording_sha256") if found["clean"]["code"] == 0 else None
    differ = [
        n
        for n in runs
        if clean is None or found[n]["code"] != 0 or found[n].get("recording_sha256") != clean
    ]
    return {"recordings_identical": not differ, "recordings_differ": differ}


def headline(found: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Issue 23's keys, from the scenarios run."""
    keys: dict[str, Any] = {}
    if "clean" in found:
        keys["rtf_lockstep_clean"] = rtf(found["clean"])
    if "rtt100" in found:
        keys["rtf_lockstep_rtt100"] = rtf(found["rtt100"])
    if "partition" in found and "clean" in found:
        p, c = found["partition"], found["clean"]
        ok = p["code"] == 0 and c["code"] == 0 and "fault" in p  # the run ended before: None
        keys["partition_5s_added_s"] = round(p["run_s"] - c["run_s"], 1) if ok else None
    if "loss10" in found:
        keys["spurious_member_lost_loss10"] = len(found["loss10"]["lost_members"])
        keys["loss10_run_s"] = found["loss10"]["run_s"]
    keys["tracebacks"] = sum(n for s in found.values() for n in s["tracebacks"].values())
    return keys | same_recordings(found)


async def main(args: argparse.Namespace) -> int:
    if reason := unavailable():
        print(f"bench/network.py: {reason}", file=sys.stderr)
        return 2
    names = SCENARIOS if args.scenario == "all" else (args.scenario,)
    out = Path(args.out or tempfile.mkdtemp(prefix="mover-network-"))
    found: dict[str, dict[str, Any]] = {}
    for name in names:
        figures = await scenario(
            name,
            out / name,
            args.seed,
            args.loss_timeout if name in LOSS else args.timeout,
            args.rtt_for,
            args.patience,
            args.control_delay,
        )
        found[name] = figures
        print(f"{name}: {json.dumps(figures)}", flush=True)
    patience = args.patience or NodeConfig().patience
    keys = {"seed": args.seed, "control_delay": args.control_delay, "patience": patience}
    keys |= {"out": str(out), **headline(found)}
    print(json.dumps({**keys, "scenarios": found}))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", choices=("all", *SCENARIOS), default="all")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--control-delay",
        type=int,
        default=CONTROL_DELAY,
        help=f"the world's control delay in ticks (default {CONTROL_DELAY}; 0: none)",
    )
    parser.add_argument("--out", help="folder for each run's logs and recording (default: a temp)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds a run may take")
    parser.add_argument(
        "--loss-timeout", type=float, default=360.0, help="seconds a loss2 or loss10 run may take"
    )
    parser.add_argument(
        "--patience", type=float, help="the team's patience in seconds (default: the default, 10)"
    )
    parser.add_argument(
        "--rtt-for", type=float, default=40.0, help="seconds the rtt100 run is given"
    )
    try:
        sys.exit(asyncio.run(main(parser.parse_args())))
    except KeyboardInterrupt:  # the lab and the team are down by now
        print("bench/network.py: interrupted", file=sys.stderr)
        sys.exit(130)
