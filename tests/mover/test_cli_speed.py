"""`mover ps`, `mover runs` and `mover call` answer as soon as the team is known: ``--wait`` is a
bound, not a pause (one liveliness query, then the holders' hellos)."""

from __future__ import annotations

import json
import time

import pytest

from mover import Node
from tests.helpers.procs import cluster
from tests.mover.test_cli import mover

pytestmark = pytest.mark.processes

BOUND = 20.0  # what each verb is allowed to wait; answering takes a small part of it


async def test_ps_runs_and_call_do_not_wait_their_bound() -> None:
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        await c.robot("r1")
        await c.robot("r2")
        await node.membership.wait_for({"r1", "r2"}, timeout=10)
        env = {**c.team.env(), **c.peer.env()}
        t0 = time.monotonic()
        code, out, err = await mover("ps", "--wait", str(BOUND), "--json", env=env)
        ps = time.monotonic() - t0
        assert code == 0, err
        assert {r["name"] for r in map(json.loads, out.splitlines())} == {"r1", "r2", "tester"}
        t0 = time.monotonic()
        code, out, err = await mover("runs", "--wait", str(BOUND), env=env)
        runs = time.monotonic() - t0
        assert code in (0, 1), err  # no runs yet: said so
        t0 = time.monotonic()
        code, out, err = await mover("call", "r2", "add", "2", "40", "--wait", str(BOUND), env=env)
        call = time.monotonic() - t0
        assert (code, out) == (0, "42\n"), err
        assert max(ps, runs, call) < BOUND / 3, (ps, runs, call)
