"""`mover up` with real processes: a team file's world, robots and program come up by
membership, log to a run folder, and go down cleanly on Ctrl-C, when a required process exits,
and when mover up itself is killed."""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import sys
import time
from pathlib import Path

import pytest

from mover._procs import Child, stop
from mover._up import _supervisor
from mover._up._plan import ProcessPlan
from tests.helpers.procs import ROOT

pytestmark = pytest.mark.processes

WORLD = ROOT / "worlds" / "search_and_rescue.toml"

SMALL = f"""\
[team]
name = "small"
seed = 5

[world]
file = "{WORLD}"

[[robots]]
names = ["ernst", "moseley"]

[program]
name = "hello_team"
"""


class Up:
    """A ``python -m mover._up`` process whose output lines are collected as they come."""

    def __init__(self, proc: asyncio.subprocess.Process) -> None:
        self.proc = proc
        self.lines: list[str] = []
        self._more = asyncio.Event()
        self._reader = asyncio.ensure_future(self._read())

    @classmethod
    async def start(cls, teamfile: Path, *args: str) -> Up:
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "mover._up", str(teamfile), *args,
            cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT,
        )  # fmt: skip
        return cls(proc)

    async def _read(self) -> None:
        assert self.proc.stdout is not None
        async for raw in self.proc.stdout:
            self.lines.append(raw.decode(errors="replace").rstrip())
            self._more.set()
        self._more.set()

    async def line(self, text: str, timeout: float = 60.0) -> str:
        """The first line containing ``text`` (waiting for it)."""
        async with asyncio.timeout(timeout):
            while True:
                found = [line for line in self.lines if text in line]
                if found:
                    return found[0]
                if self._reader.done():
                    raise AssertionError(f"{text!r} never came:\n" + self.text)
                self._more.clear()
                await self._more.wait()

    async def ended(self, timeout: float = 30.0) -> int:
        async with asyncio.timeout(timeout):
            code = await self.proc.wait()
            await self._reader
        return code

    @property
    def text(self) -> str:
        return "\n".join(self.lines)

    def pids(self) -> dict[str, int]:
        """The processes mover up said it started."""
        found = (re.search(r"\[up\] started (\S+) \(pid (\d+)\)", line) for line in self.lines)
        return {m.group(1): int(m.group(2)) for m in found if m}


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


async def gone(pids: dict[str, int], timeout: float = 5.0) -> list[str]:
    """The names of the processes still alive after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and any(alive(p) for p in pids.values()):
        await asyncio.sleep(0.1)
    return [name for name, pid in pids.items() if alive(pid)]


async def test_a_team_comes_up_runs_its_program_and_stops_on_ctrl_c(tmp_path: Path) -> None:
    (tmp_path / "small.toml").write_text(SMALL)
    out = tmp_path / "run"
    up = await Up.start(tmp_path / "small.toml", "--out", str(out))
    try:
        ready = await up.line("[up] ready in")
        await up.line("[hello_team] ended")
    finally:
        up.proc.send_signal(signal.SIGINT)
    code = await up.ended()
    text = up.text
    assert code == 0, text
    pids = up.pids()
    assert set(pids) == {"world", "ernst", "moseley"}, text
    assert await gone(pids, 1.0) == [], text  # every process reaped by mover up, none orphaned
    # readiness came from membership, before the program started, and the program ran
    assert text.index("[up] ready in") < text.index("[hello_team] hello_team on ernst, moseley")
    assert "ernst: heard who=['moseley']" in text and "moseley: {" in text
    assert "[up] Ctrl-C: stopping the team" in text
    assert re.search(r"\[up\] stopped 3 processes in \d+\.\d s", text), text
    print(ready)
    logs = {p.name for p in out.glob("*.log")}
    assert logs == {"world.log", "ernst.log", "moseley.log"}
    for log in out.glob("*.log"):
        assert "Traceback" not in log.read_text(), log.read_text()
    assert "READY world" in (out / "world.log").read_text()
    assert "Traceback" not in text
    resolved = json.loads((out / "team.json").read_text())
    assert resolved["seeds"]["run"] == 5 and resolved["world"]["expect"] == 2
    assert resolved["topology"] == "peer"
    assert len((out / "team.key").read_text().strip()) == 64  # a fresh key, kept for others


async def test_a_required_process_that_exits_stops_the_team(tmp_path: Path) -> None:
    text = SMALL.replace(
        'names = ["ernst", "moseley"]', 'names = ["ernst", "moseley"]\nrequired = true'
    )
    (tmp_path / "t.toml").write_text(text.split("[program]")[0])
    up = await Up.start(tmp_path / "t.toml", "--out", str(tmp_path / "run"))
    try:
        await up.line("[up] ready in")
        pids = up.pids()
        os.kill(pids["moseley"], signal.SIGKILL)
        killed = time.monotonic()
        code = await up.ended()
    finally:
        if up.proc.returncode is None:
            up.proc.kill()
    assert code == 1, up.text
    assert time.monotonic() - killed < 10
    assert "mover up: the moseley process was killed by signal 9" in up.text
    assert await gone(pids, 1.0) == []
    assert "Traceback" not in up.text


async def test_the_world_rejecting_its_file_fails_mover_up_at_once(tmp_path: Path) -> None:
    (tmp_path / "bad.toml").write_text('[world]\nname = "bad"\nsize = [1e7, 1e7]\n')
    (tmp_path / "t.toml").write_text(SMALL.replace(str(WORLD), str(tmp_path / "bad.toml")))
    t0 = time.monotonic()
    up = await Up.start(tmp_path / "t.toml", "--out", str(tmp_path / "run"))
    code = await up.ended()
    assert code == 1, up.text
    assert time.monotonic() - t0 < 10  # two Python starts on a busy machine; no wait for a bound
    said = [line for line in up.lines if line.startswith("mover up: the world process exited")]
    assert len(said) == 1, up.text
    # the world's own words
    assert (
        "bad.toml:3: world.size: must be a list of 2 numbers, each > 0 and at most 1000" in said[0]
    )
    assert await gone(up.pids(), 1.0) == []
    assert "Traceback" not in up.text


async def test_a_large_team_runs_behind_a_router_and_leaves_no_orphan_when_killed(
    tmp_path: Path,
) -> None:
    """Twelve workstations and mover up itself: 13 members, over PEER_MESH_MAX (12)."""
    (tmp_path / "t.toml").write_text(
        '[team]\nname = "hub"\n[[workstations]]\nprefix = "w"\ncount = 12\n'
    )
    up = await Up.start(tmp_path / "t.toml", "--out", str(tmp_path / "run"))
    try:
        await up.line("[up] ready in")
        pids = up.pids()
        assert set(pids) == {"router", *(f"w{i}" for i in range(1, 13))}, up.text
        assert "; router on 127.0.0.1:" in up.text
        team = json.loads((tmp_path / "run" / "team.json").read_text())
        assert team["topology"] == "router"
        up.proc.kill()  # no chance to stop anyone: the children must notice by themselves
        await up.ended()
    finally:
        if up.proc.returncode is None:
            up.proc.kill()
    assert await gone(pids, 10.0) == [], up.text


async def test_the_foraging_team_file_runs_once_and_stops(tmp_path: Path) -> None:
    up = await Up.start(
        ROOT / "teams" / "foraging.toml", "--exit-after-run", "--out", str(tmp_path / "run")
    )
    code = await up.ended(timeout=90)
    assert code == 0, up.text
    results = [line for line in up.lines if re.match(r"\[forage\] f\d: \{", line)]
    assert len(results) == 4, up.text
    delivered = sum(json.loads(line.split(": ", 1)[1])["delivered"] for line in results)
    assert delivered == 200, up.text  # two resources of 100 units, all brought home
    assert "[forage] ended after" in up.text
    assert await gone(up.pids(), 1.0) == []
    assert "Traceback" not in up.text


DESKS = '[team]\nname = "desks"\n[[workstations]]\nprefix = "w"\ncount = 2\n'


async def test_sigterm_stops_the_team_with_status_0(tmp_path: Path) -> None:
    (tmp_path / "t.toml").write_text(DESKS)
    up = await Up.start(tmp_path / "t.toml", "--out", str(tmp_path / "run"))
    try:
        await up.line("[up] ready in")
    finally:
        up.proc.terminate()
    assert await up.ended() == 0, up.text
    assert "[up] SIGTERM: stopping the team" in up.text
    assert await gone(up.pids(), 1.0) == []
    assert "Traceback" not in up.text


async def test_a_run_that_fails_makes_exit_after_run_exit_1(tmp_path: Path) -> None:
    program = '[program]\nname = "hello_team"\nmembers = ["w1", "w2"]\nargs = { bogus = 1 }\n'
    (tmp_path / "t.toml").write_text(DESKS + program)
    up = await Up.start(tmp_path / "t.toml", "--exit-after-run", "--out", str(tmp_path / "run"))
    assert await up.ended() == 1, up.text
    assert "[hello_team] not started: BadArguments:" in up.text
    assert await gone(up.pids(), 1.0) == []
    assert "Traceback" not in up.text


async def test_a_process_that_ignores_sigint_and_sigterm_is_killed_after_the_bounds(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_supervisor, "STOP_GRACE", 0.3)
    monkeypatch.setattr(_supervisor, "KILL_GRACE", 0.3)
    stubborn = (
        "import signal, sys, time\n"
        "signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
        "signal.signal(signal.SIGTERM, signal.SIG_IGN)\n"
        "print('READY', flush=True)\n"
        "time.sleep(60)\n"
    )
    plan = ProcessPlan("stubborn", (sys.executable, "-c", stubborn), required=False)
    proc = await asyncio.create_subprocess_exec(
        *plan.argv, stdout=asyncio.subprocess.PIPE, start_new_session=True
    )
    assert proc.stdout is not None
    assert await asyncio.wait_for(proc.stdout.readline(), 20) == b"READY\n"
    child = Child(plan.name, proc, tmp_path / "log", group=True)  # its own session, as in up
    t0 = time.monotonic()
    await stop([child], _supervisor._stop_ladder())
    assert proc.returncode == -signal.SIGKILL
    assert 0.6 <= time.monotonic() - t0 < 5
