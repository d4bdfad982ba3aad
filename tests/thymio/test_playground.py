"""The Thymio backend against Aseba Playground: each device, the program as processes (from the
pytest plugin and from ``mover up``), and the Playground killed and brought back.

Ground truth comes from the world's geometry only (the Aseba protocol tells no poses): a wall
at a known place, dark stripes on the floor at known places, the edge of a dark half-plane.
"""

from __future__ import annotations

import asyncio
import json
import math
import signal
import sys
import tomllib
from pathlib import Path
from typing import Any

import pytest

from mover import launch
from mover._config import free_port
from mover.testing import cluster
from robots.hal import HardwareLost
from robots.thymio import ThymioHardware, connect
from robots.thymio._link import Address, AsebaLink
from robots.thymio.playground import PlaygroundRobot, ground_png, stop_playground, world_xml

from .conftest import ROOT, Playground, needs_playground, shipped_world

pytestmark = [pytest.mark.processes, needs_playground]

STRIPES = (0.50, 0.80)  # x of the runner's two dark stripes (2 cm wide, y from 0 to 0.4)
EDGE = (1.30, 0.80)  # the spinner stands here, on the edge of the dark half-plane y > 0.8


async def _connect(r: PlaygroundRobot) -> ThymioHardware:
    """Connect as a robot process does: again while the robot does not answer (a Playground
    serves a port's next client only a moment after the last one left)."""
    async with asyncio.timeout(20):
        while True:
            try:
                return await connect(
                    r.name, f"tcp:127.0.0.1:{r.port}", spec={"pose": [r.x, r.y, r.heading]}
                )
            except HardwareLost:
                await asyncio.sleep(0.5)


async def _ticks(hw: ThymioHardware, seconds: float) -> None:
    await hw.clock.sleep(seconds)


async def test_each_device_against_the_playground(tmp_path: Path, playground: Playground) -> None:
    """Wall nearer than open floor; speeds reached; odometry over 0.30 m of known floor within
    2 cm; odometry over a full turn, timed by the floor, within 0.3 rad."""
    wall = PlaygroundRobot("wall", 0.3, 1.5 - 0.12, math.pi / 2, free_port())  # 4 cm off
    runner = PlaygroundRobot("runner", 0.25, 0.2, 0.0, free_port())
    spinner = PlaygroundRobot("spinner", *EDGE, 0.0, free_port())
    robots = [wall, runner, spinner]
    dark = [(x - 0.01, 0.0, x + 0.01, 0.4) for x in STRIPES] + [(1.0, EDGE[1], 1.6, 1.2)]
    (tmp_path / "floor.png").write_bytes(ground_png((1.6, 1.52), dark))
    world = tmp_path / "devices.playground"
    world.write_text(world_xml(robots, size=(1.6, 1.52), walls=[(0.8, 1.51, 1.6, 0.02)],
                               ground="floor.png"))  # fmt: skip
    await playground(world, [r.port for r in robots])
    near, run, spin = [await _connect(r) for r in robots]  # one after the other
    await asyncio.gather(_ticks(near, 0.3), _ticks(spin, 0.3))
    assert near.sonar is not None and spin.sonar is not None
    assert near.sonar.ranges()[2] < 0.06 < spin.sonar.max_range == spin.sonar.ranges()[2]
    assert min(run.ground.reflectance()) > 0.8  # white floor under the runner's sensors
    assert not near.buttons.pressed()

    async def straight() -> list[float]:
        """x (odometry) at each stripe's leading edge; the measured speed on the way."""
        run.drive.set_velocity(0.1, 0.0)
        seen: list[float] = []
        was = False
        try:
            while len(seen) < 2 and run.clock.now() < start + 10:
                await run.clock.tick()
                dark = run.ground.reflectance()[0] < 0.5
                if dark and not was:
                    seen.append(run.odometry.pose()[0])
                was = dark
        finally:
            run.drive.stop()
        v, w = run.calibration.motion(*run.sonar.readings.speeds)  # type: ignore[union-attr]
        assert v == pytest.approx(0.1, abs=0.005) and abs(w) < 0.05  # speeds reached
        return seen

    async def turn() -> list[float]:
        """Heading (odometry) at each crossing of the half-plane's edge by the left sensor."""
        spin.drive.set_velocity(0.0, 2.0)
        seen: list[float] = []
        was = spin.ground.reflectance()[0] < 0.5
        try:
            while len(seen) < 3 and spin.clock.now() < start + 10:
                await spin.clock.tick()
                dark = spin.ground.reflectance()[0] < 0.5
                if dark != was:
                    seen.append(spin.odometry.pose()[2])
                was = dark
        finally:
            spin.drive.stop()
        return seen

    start = run.clock.now()
    xs, headings = await asyncio.gather(straight(), turn())
    await asyncio.gather(_ticks(run, 0.1), _ticks(spin, 0.1))
    assert len(xs) == 2 and xs[1] - xs[0] == pytest.approx(STRIPES[1] - STRIPES[0], abs=0.02)
    assert len(headings) == 3 and headings[2] - headings[0] == pytest.approx(2 * math.pi, abs=0.3)
    for hw in (near, run, spin):
        await hw.clock.tick()  # (stopped)


def _entries(ports: list[int]) -> list[dict[str, Any]]:
    """The [[robots]] entries of teams/thymio_gather.toml, each linked to its port."""
    entries: list[dict[str, Any]] = tomllib.loads(
        (ROOT / "teams" / "thymio_gather.toml").read_text()
    )["robots"]
    for e, port in zip(entries, ports, strict=True):
        e["options"] = {**e.get("options", {}), "link": f"tcp:127.0.0.1:{port}"}
    return entries


async def _robots(mover_cluster: Any, entries: list[dict[str, Any]]) -> list[Any]:
    return list(
        await asyncio.gather(
            *(
                mover_cluster.start(
                    "robots",
                    "--name",
                    e["names"][0],
                    "--hardware",
                    "thymio",
                    "--option",
                    f"link={e['options']['link']}",
                    "--spec",
                    json.dumps(e["spec"]),
                    label=e["names"][0],
                )
                for e in entries
            )
        )
    )


def _check_gathered(outcomes: dict[str, Any]) -> None:
    results = {m: o.get("result") for m, o in outcomes.items()}
    assert all(r is not None for r in results.values()), outcomes
    assert len({r["winner"] for r in results.values()}) == 1
    for r in results.values():
        assert r["from_patch"] < 0.3, results


@pytest.mark.timeout(120)
async def test_three_thymios_gather_as_processes_of_the_pytest_plugin(
    tmp_path: Path, playground: Playground, mover_cluster: Any, mover_launcher: Any
) -> None:
    world, ports = shipped_world(tmp_path)
    await playground(world, ports)
    entries = _entries(ports)
    await _robots(mover_cluster, entries)
    names = [e["names"][0] for e in entries]
    outcomes = await asyncio.wait_for(
        launch(mover_launcher, "thymio_gather", names, {}, run="g", seed=1), 90
    )
    _check_gathered(outcomes)


@pytest.mark.timeout(120)
async def test_three_thymios_gather_from_mover_up_from_nothing(tmp_path: Path) -> None:
    """``mover up teams/thymio_gather.toml --exit-after-run`` as shipped: the team file starts
    the Playground on free ports, the robots and the program, and stops them all."""
    team = ROOT / "teams" / "thymio_gather.toml"
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", "up", str(team), "--exit-after-run",
        "--out", str(tmp_path / "up"),
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT,
    )  # fmt: skip
    try:
        out, _ = await asyncio.wait_for(proc.communicate(), 100)  # 30 s typical: the search
    finally:
        if proc.returncode is None:
            proc.send_signal(signal.SIGINT)
            await proc.wait()
    text = out.decode(errors="replace")
    assert proc.returncode == 0, text
    ready = next(ln for ln in text.splitlines() if "[playground] playground ready: " in ln)
    ports = dict(p.split("=") for p in ready.split("ready: ", 1)[1].split())
    assert list(ports) == ["t1", "t2", "t3"] and "33333" not in ports.values()  # free ports
    argv = {
        p["name"]: p["argv"]
        for p in json.loads((tmp_path / "up" / "team.json").read_text())["processes"]
    }
    outcomes = {}
    for name, port in ports.items():
        assert f'link="tcp:127.0.0.1:{port}"' in argv[name]  # each robot linked by its name
        line = next(ln for ln in text.splitlines() if f"[gather] {name}: " in ln)
        outcomes[name] = {"result": json.loads(line.split(f"[gather] {name}: ", 1)[1])}
    _check_gathered(outcomes)
    assert "Traceback" not in text
    for number in ports.values():  # the Playground stopped with the team
        with pytest.raises(ConnectionRefusedError):
            await asyncio.open_connection("127.0.0.1", int(number))


@pytest.mark.timeout(120)
async def test_the_playground_killed_mid_run_and_back(
    tmp_path: Path, playground: Playground, mover_cluster: Any, mover_launcher: Any
) -> None:
    """One line per robot, HardwareLost at the launcher, reconnection, Ctrl-C stops the motors."""
    world, ports = shipped_world(tmp_path)
    first = await playground(world, ports)
    entries = _entries(ports)
    procs = await _robots(mover_cluster, entries)
    names = [e["names"][0] for e in entries]
    logs = [tmp_path / "mover-logs" / f"{name}.log" for name in names]
    running = asyncio.ensure_future(
        launch(mover_launcher, "thymio_gather", names, {}, run="k1", seed=1)
    )
    await asyncio.sleep(2.0)
    await stop_playground(first, signal.SIGKILL)
    outcomes = await asyncio.wait_for(running, 20)
    errors = {name: str(o.get("error", "")) for name, o in outcomes.items()}
    cut = {name for name, e in errors.items() if "HardwareLost" in e}
    assert cut, outcomes  # the robots' own loss, in one line each; a robot whose run a
    # lost one's ended first (it says it left the run) ends MemberLost naming it instead
    assert all(
        n in cut or ("MemberLost" in e and any(m in e for m in cut)) for n, e in errors.items()
    ), outcomes
    await playground(world, ports)
    await _until_logged(logs, "back in the world")
    # Ctrl-C in a run: the motors stop on the way out, and the others' runs end.
    running = asyncio.ensure_future(
        launch(mover_launcher, "thymio_gather", names, {}, run="k2", seed=1)
    )
    await asyncio.sleep(2.0)
    mover_cluster.kill(procs[0], signal.SIGINT)
    assert await asyncio.wait_for(procs[0].wait(), 15) in (0, 130)
    link = await AsebaLink.open(Address.parse(entries[0]["options"]["link"]), None, 5.0)
    offset, _ = link.variables["motor.left.target"]
    assert await link.read(offset, 2, 2.0) == (0, 0)  # stopped on the way out
    await link.aclose()
    outcomes = await asyncio.wait_for(running, 30)
    assert not any("result" in o for o in outcomes.values()), outcomes
    for log in logs:
        text = log.read_text()
        assert "Traceback" not in text, text
        lost = [ln for ln in text.splitlines() if "waiting for it to come back" in ln]
        assert len(lost) == 1 and "Thymio" in lost[0], text


async def _until_logged(logs: list[Path], words: str) -> None:
    async with asyncio.timeout(20):
        while not all(words in log.read_text() for log in logs):
            await asyncio.sleep(0.2)


@pytest.mark.timeout(90)
async def test_a_program_that_needs_a_camera_fails_at_start_on_a_thymio(
    tmp_path: Path, playground: Playground
) -> None:
    """``@needs("camera")`` on a Thymio robot process: one line at the robot, one at the
    launcher, naming the device; no traceback; the robot stays up (nothing was lost)."""
    robot = PlaygroundRobot("t1", 0.5, 0.5, 0.0, free_port())
    world = tmp_path / "one.playground"
    world.write_text(world_xml([robot]))
    await playground(world, [robot.port])
    logs = tmp_path / "logs"
    async with cluster(cwd=ROOT, logs=logs) as c, c.launcher() as node:
        proc = await c.start(
            "tests.thymio.camera_robot", "t1", f"tcp:127.0.0.1:{robot.port}", label="t1"
        )
        outcomes = await asyncio.wait_for(launch(node, "look", ["t1"], {}, run="cam"), 30)
        assert proc.returncode is None  # the process stays: a missing device is not a lost robot
    outcome = outcomes["t1"]
    assert outcome["error"].startswith(
        "MissingDevice: program look needs a camera; the robot's hardware (ThymioHardware) "
        "has none (it has: clock, drive, odometry, sonar, led, radio, ground, buttons, leds"
    ), outcome
    assert "\n" not in outcome["error"] and "traceback" not in outcome
    text = (logs / "t1.log").read_text()
    said = [ln for ln in text.splitlines() if "needs a camera" in ln]
    assert len(said) == 1 and "run cam failed: MissingDevice" in said[0], text
    assert "Traceback" not in text and "waiting for it to come back" not in text
