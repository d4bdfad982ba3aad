"""Run control with real member processes over real zenoh on 127.0.0.1: a busy member refuses
a second run unless both share, cancel runs the program's ``finally``, ``mover runs``,
``mover ps``, ``mover run --attach`` and ``mover cancel`` see a run under way, ``mover run``
warns when the team it finds changed, and the run's seed gives every member the same draws."""

from __future__ import annotations

import asyncio
import os
import random
import signal
import sys
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from mover import BadArguments, Node, Refused, RunTeam, launch
from mover._collective import seed_of
from mover._programs import outcomes
from tests.helpers.clocks import UnmodelledHold
from tests.helpers.procs import ROOT, Cluster, cluster

pytestmark = pytest.mark.processes

MEMBER = "tests.mover._run_member"


async def start_members(c: Cluster, node: Node, names: list[str]) -> None:
    await asyncio.gather(*(c.start(MEMBER, n) for n in names))
    await node.membership.wait_for(names, timeout=30)


async def mover(c: Cluster, tmp: Path, *args: str, bound: float = 40.0) -> tuple[int, str, str]:
    """Run the real ``mover`` command as a member of the cluster's team."""
    env = {
        **os.environ,
        **c.env,
        **c.team.env(),
        **c.peer.env(),
        "MOVER_STATE_DIR": str(tmp / "state"),
    }
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *args, env=env, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    out, err = await asyncio.wait_for(proc.communicate(), bound)
    assert proc.returncode is not None
    return proc.returncode, out.decode(), err.decode()


async def wait_phase(node: Node, member: str, run: str, phase: str) -> None:
    async with asyncio.timeout(20):
        while True:
            runs = await node.call(member, "mover.status", timeout=5)
            if any(r["run"] == run and r["phase"] == phase for r in runs):
                return
            await asyncio.sleep(0.05)


# -- seeds (no network) ---------------------------------------------------------------------------


def _team(me: str, run: str, seed: int | None = None) -> RunTeam:
    node: Any = SimpleNamespace(name=me)
    return RunTeam(node, run, ["a", "b"], collectives=object(), seed=seed)  # type: ignore[arg-type]


def test_the_rng_depends_on_seed_member_and_stream_not_on_the_run_name() -> None:
    def draws(t: RunTeam, stream: str = "") -> list[float]:
        rng = t.rng(stream)
        return [rng.random() for _ in range(5)]

    assert draws(_team("a", "r1", 7)) == draws(_team("a", "other", 7))
    assert draws(_team("a", "r1", 7)) != draws(_team("b", "r1", 7))
    assert draws(_team("a", "r1", 7)) != draws(_team("a", "r1", 8))
    assert draws(_team("a", "r1", 7), "walk") != draws(_team("a", "r1", 7), "turn")
    assert _team("a", "r1").seed == seed_of("r1") == _team("b", "r1").seed
    assert _team("a", "r1").seed != _team("a", "r2").seed
    with pytest.raises(ValueError, match="seed"):
        _team("a", "r1", -1)


# -- processes -------------------------------------------------------------------------------------


async def test_a_launch_seed_reaches_every_member_as_processes() -> None:
    async with cluster() as c, c.launcher() as node:
        await start_members(c, node, ["a", "b"])
        first = await launch(node, "draw", ["a", "b"], {"n": 3}, run="d1", seed=7)
        again = await launch(node, "draw", ["a", "b"], {"n": 3}, run="d2", seed=7)
        default = await launch(node, "draw", ["a", "b"], {"n": 1}, run="d3")
    for member in ("a", "b"):
        rng = random.Random(f"7/{member}/x")
        assert first[member]["result"] == {"seed": 7, "draws": [rng.random() for _ in range(3)]}
        assert again[member]["result"] == first[member]["result"]
        assert default[member]["result"]["seed"] == seed_of("d3")
    begins = [o["steps"][0] for o in first.values()]  # every run starts with the barrier
    assert all(b["step"] == 0 and b["kind"] == "begin" for b in begins)
    assert sum(b["messages"] for b in begins) == 2  # 2(n-1)


async def test_busy_refusal_share_and_cancel(tmp_path: Path) -> None:
    async with cluster() as c, c.launcher() as node:
        await start_members(c, node, ["a", "b"])
        marks = {"marker_dir": str(tmp_path)}
        await launch(node, "hold", ["a"], marks, run="r1", wait=False)
        await wait_phase(node, "a", "r1", "holding")

        with pytest.raises(BadArguments, match="policy must be one of fail, survivors"):
            await launch(node, "pause", ["b"], {}, run="rp", policy="maybe")  # type: ignore[arg-type]
        with pytest.raises(Refused, match=r"busy in run 'r1'.*share") as refused:
            await launch(node, "pause", ["a", "b"], {"seconds": 0.1}, run="r2")
        print(f"\nrefused: {refused.value}")
        await asyncio.sleep(0.3)
        b_runs = {r["run"]: r["state"] for r in await node.call("b", "mover.status", timeout=5)}
        assert b_runs.get("r2") in ("cancelled", None)  # b had started: the launch ended it
        assert (tmp_path / "r1.a").read_text() == "started"  # r1 goes on

        t0 = time.monotonic()
        outcome = await node.call("a", "mover.cancel", "r1", "the test", timeout=20)
        print(f"cancelled in {time.monotonic() - t0:.2f} s: {outcome}")
        assert outcome["error"] == "cancelled by the test"
        assert (tmp_path / "r1.a").read_text() == "cleaned"  # its finally ran
        states = {r["run"]: r["state"] for r in await node.call("a", "mover.status", timeout=5)}
        assert states["r1"] == "cancelled"

        # shared runs run side by side; an unshared one is still refused beside them
        await launch(node, "hold", ["a"], marks, run="r3", wait=False, share=True)
        await wait_phase(node, "a", "r3", "holding")
        beside = await launch(node, "pause", ["a"], {"seconds": 0.1}, run="r4", share=True)
        assert beside["a"]["result"] == "a"
        with pytest.raises(Refused, match="busy in run 'r3'"):
            await launch(node, "pause", ["a"], {"seconds": 0.1}, run="r5")
        await node.call("a", "mover.cancel", "r3", "the test", timeout=20)
        assert (tmp_path / "r3.a").read_text() == "cleaned"
        after = await launch(node, "pause", ["a"], {"seconds": 0.0}, run="r6")  # free again
        assert after["a"]["result"] == "a"


async def test_the_cli_sees_attaches_to_and_cancels_a_run(tmp_path: Path) -> None:
    async with cluster() as c, c.launcher() as node:
        await start_members(c, node, ["a", "b"])
        await launch(
            node, "hold", ["a", "b"], {"marker_dir": str(tmp_path)}, run="busy", wait=False
        )
        await wait_phase(node, "b", "busy", "holding")

        code, out, err = await mover(c, tmp_path, "runs", "--wait", "1")
        print(f"\n$ mover runs\n{out}{err}")
        assert code == 0, err
        line = next(x for x in out.splitlines() if x.startswith("busy "))
        assert "hold" in line and "a=running:holding" in line and "b=running:holding" in line

        code, out, err = await mover(c, tmp_path, "ps", "--wait", "1")
        print(f"$ mover ps\n{out}{err}")
        assert code == 0, err
        rows = {x.split()[0]: x for x in out.splitlines()[1:]}
        assert "busy" in rows["a"] and "holding" in rows["a"]
        assert "busy" in rows["b"] and "holding" in rows["b"]

        code, out, err = await mover(c, tmp_path, "cancel", "busy", "--wait", "1")
        print(f"$ mover cancel busy\n{out}{err}")
        assert code == 0, err
        assert "a: FAILED cancelled by mover cancel" in out
        assert "b: FAILED cancelled by mover cancel" in out
        for member in ("a", "b"):
            assert (tmp_path / f"busy.{member}").read_text() == "cleaned"

        code, out, err = await mover(c, tmp_path, "cancel", "nothing-here", "--wait", "1")
        assert code == 1 and "knows run 'nothing-here'" in err and len(err.splitlines()) == 1

        # a run started detached, followed again from another launcher
        code, out, err = await mover(
            c, tmp_path, "run", "pause", "--args", '{"seconds": 4}', "--run-id", "later",
            "--detach", "--wait", "1",
        )  # fmt: skip
        assert code == 0, err
        assert "mover run --attach later" in out
        code, out, err = await mover(c, tmp_path, "run", "--attach", "later", "--wait", "1")
        print(f"$ mover run --attach later\n{out}{err}")
        assert code == 0, err
        assert "a: waking after=4.00" in out and "b: waking after=4.00" in out
        assert out.rstrip().splitlines()[-2:] == ['a: "a"', 'b: "b"']

        code, out, err = await mover(c, tmp_path, "run", "--attach", "later", "pause")
        assert code == 2 and "not both" in err


async def test_ctrl_c_on_mover_run_says_the_run_goes_on_and_how_to_reach_it(
    tmp_path: Path,
) -> None:
    async with cluster() as c, c.launcher() as node:
        await start_members(c, node, ["a", "b"])
        env = {**os.environ, **c.env, **c.team.env(), **c.peer.env()}
        env["MOVER_STATE_DIR"] = str(tmp_path / "state")
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "mover", "run", "pause", "--args", '{"seconds": 30}',
            "--run-id", "long", "--wait", "5", env=env, cwd=ROOT,
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )  # fmt: skip
        try:
            await wait_phase(node, "b", "long", "pausing")
            proc.send_signal(signal.SIGINT)
            _, err = await asyncio.wait_for(proc.communicate(), 15)
        finally:
            if proc.returncode is None:
                proc.kill()
                await proc.wait()
        assert proc.returncode == 130, err
        said = err.decode()
        assert "run long goes on on the members" in said and "Traceback" not in said
        assert "mover run --attach long" in said and "mover cancel long" in said
        code, _, err_ = await mover(c, tmp_path, "cancel", "long", "--wait", "1")
        assert code == 0, err_


async def test_mover_run_warns_when_the_team_changed(tmp_path: Path) -> None:
    async with cluster() as c, c.launcher() as node:
        await start_members(c, node, ["a", "b"])
        args = ("run", "pause", "--args", '{"seconds": 0}', "--wait", "1.5")
        code, out, err = await mover(c, tmp_path, *args)
        assert code == 0, out + err
        assert "warning" not in err  # the first run of the team: nothing to compare with
        code, out, err = await mover(c, tmp_path, *args)
        assert code == 0 and "warning" not in err  # the same team
        await start_members(c, node, ["c"])
        c.procs[0].kill()  # a leaves
        await node.membership.wait_gone("a", timeout=10)
        code, out, err = await mover(c, tmp_path, *args)
        print(f"\n$ mover run pause (a gone, c new)\n{out}{err}")
        assert code == 0, out + err
        warnings = [x for x in err.splitlines() if "warning" in x]
        assert len(warnings) == 1
        assert "missing a" in warnings[0] and "new c" in warnings[0]
        assert 'b: "b"' in out and 'c: "c"' in out


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (["run", "pause", "--seed", "-1"], "--seed"),
        (["run", "pause", "--seed", "x"], "--seed"),
        (["run"], "a PROGRAM to start is needed"),
        (["run", "--attach", "a/b*"], "--attach"),
        (["cancel", "a b"], "run"),
    ],
)
async def test_bad_run_control_inputs_get_one_line_and_exit_2(
    tmp_path: Path, args: list[str], said: str
) -> None:
    env = {**os.environ, "MOVER_TEAM": "alpha", "MOVER_TEAM_KEY": "00" * 32}
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *args, env=env, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    out, err = await asyncio.wait_for(proc.communicate(), 20)
    text = (out + err).decode()
    assert proc.returncode == 2, text
    assert "Traceback" not in text
    assert len([x for x in err.decode().splitlines() if x.startswith("mover") and said in x]) == 1


# -- the host's clock (in-process nodes) ----------------------------------------------------------


class CountingClock(UnmodelledHold):
    """A :class:`mover.RunClock` that counts engages and releases."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def now(self) -> float:
        return 1.5

    async def passed(self, t: float) -> None:
        return None

    async def engage(self) -> None:
        self.calls.append("engage")

    def release(self) -> None:
        self.calls.append("release")


async def test_the_host_engages_its_clock_per_run_and_releases_it_after_the_last() -> None:
    from mover import NodeConfig, ProgramHost, TeamCredentials
    from mover._config import free_port

    gate = asyncio.Event()

    async def wait_gate(robot: None, team: RunTeam) -> float:
        await gate.wait()
        assert team.clock is not None and team.simulated  # every member has a clock
        return team.clock.now()

    async def fail(robot: None, team: RunTeam) -> None:
        raise RuntimeError("on purpose")

    port = free_port()
    async with Node(
        "h", TeamCredentials.generate("t"), config=NodeConfig(listen=(f"tcp/127.0.0.1:{port}",))
    ) as node:
        host = ProgramHost(node, {"wait_gate": wait_gate, "fail": fail}, robot=None)
        clock = host.clock = CountingClock()
        for program, run in (("fail", "f1"), ("wait_gate", "w1")):
            if program == "wait_gate":
                gate.set()
            outcome = await launch(node, program, ["h"], {}, run=run)
            assert list(outcome["h"]) == (
                ["error", "steps", "traceback"] if run == "f1" else ["result", "steps"]
            )
        assert clock.calls == ["engage", "release"] * 2  # a failed run releases it too

        gate.clear()  # two shared runs: one engage, one release after the last
        await launch(node, "wait_gate", ["h"], {}, run="s1", wait=False, share=True)
        await launch(node, "wait_gate", ["h"], {}, run="s2", wait=False, share=True)
        await asyncio.sleep(0.2)
        assert clock.calls[4:] == ["engage"]
        cancelled = await host.cancel("s1", "the test")
        assert cancelled["error"] == "cancelled by the test"
        assert clock.calls[4:] == ["engage"]  # s2 still runs
        await launch(node, "wait_gate", ["h"], {}, run="s3", wait=False, share=True)
        gate.set()
        ends = await outcomes(node, "s2", ["h"]), await outcomes(node, "s3", ["h"])
        assert [e["h"]["result"] for e in ends] == [1.5, 1.5]
        assert clock.calls[4:] == ["engage", "release"]
        assert [r["state"] for r in host.status()] == [
            "failed",
            "done",
            "cancelled",
            "done",
            "done",
        ]
