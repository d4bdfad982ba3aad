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


#: Where the proximity sensors sit on the body, fitted from walls 10, 12 and 16 cm ahead of the
#: centre (docs/thymio.md, Calibration): sensors 1 and 3 this far ahead of the centre, 0 and
#: 4 this far, the back ones this far behind.
AHEAD_1_3, AHEAD_0_4, BEHIND_5_6 = 0.075, 0.062, 0.0295


def _along_axis(wall: float, ahead: float, angle: float) -> float:
    """How far a sensor ``ahead`` of the centre, at ``angle`` off the heading, sees a wall
    square to the heading ``wall`` metres ahead of the centre, along its axis."""
    return (wall - ahead) / math.cos(angle)


async def test_each_device_against_the_playground(tmp_path: Path, playground: Playground) -> None:
    """Each HAL device against the world's geometry (tolerances in docs/thymio.md):

    * proximity: a wall 12 cm ahead of the centre read at its distance along each front
      sensor's axis (sensor 2 within 5 mm of 0.04 m, 1 and 3 within 5 mm, 0 and 4 within
      8 mm), a wall 7 cm behind by both back sensors within 5 mm of 0.0405 m, nothing in the
      open; the ground sensors on white floor;
    * buttons: one set over Aseba reads as pressed through the HAL, and released;
    * LEDs: what the HAL set is what the robot's LED program applied (read back over Aseba);
    * drive: 0.1 m/s reached within 5 mm/s (measured wheel speeds), 2 rad/s reached within
      0.1 rad/s (measured) and within 10% by the floor (a turn timed between two crossings
      of a dark edge);
    * odometry: over 0.30 m between two stripes within 2 cm, over a full turn within 0.3 rad.
    """
    wall = PlaygroundRobot("wall", 0.3, 1.5 - 0.12, math.pi / 2, free_port())  # 4 cm off
    back = PlaygroundRobot("back", 0.9, 1.5 - 0.07, -math.pi / 2, free_port())
    runner = PlaygroundRobot("runner", 0.25, 0.2, 0.0, free_port())
    spinner = PlaygroundRobot("spinner", *EDGE, 0.0, free_port())
    robots = [wall, back, runner, spinner]
    dark = [(x - 0.01, 0.0, x + 0.01, 0.4) for x in STRIPES] + [(1.0, EDGE[1], 1.6, 1.2)]
    (tmp_path / "floor.png").write_bytes(ground_png((1.6, 1.52), dark))
    world = tmp_path / "devices.playground"
    world.write_text(world_xml(robots, size=(1.6, 1.52), walls=[(0.8, 1.51, 1.6, 0.02)],
                               ground="floor.png"))  # fmt: skip
    await playground(world, [r.port for r in robots])
    near, behind, run, spin = [await _connect(r) for r in robots]  # one after the other
    await asyncio.gather(*(_ticks(hw, 0.3) for hw in (near, behind, run, spin)))
    assert near.sonar is not None and behind.sonar is not None and spin.sonar is not None
    reach = near.sonar.max_range
    r0, r1, r2, r3, r4, r5, r6 = near.sonar.ranges()
    angles = near.sonar.angles
    assert r2 == pytest.approx(_along_axis(0.12, 0.08, 0.0), abs=0.005)
    for r, a in ((r1, angles[1]), (r3, angles[3])):
        assert r == pytest.approx(_along_axis(0.12, AHEAD_1_3, a), abs=0.005)
    for r, a in ((r0, angles[0]), (r4, angles[4])):
        assert r == pytest.approx(_along_axis(0.12, AHEAD_0_4, a), abs=0.008)
    assert r5 == r6 == reach  # nothing behind
    *front, b5, b6 = behind.sonar.ranges()
    assert front == [reach] * 5
    assert b5 == pytest.approx(0.07 - BEHIND_5_6, abs=0.005)
    assert b6 == pytest.approx(0.07 - BEHIND_5_6, abs=0.005)
    assert spin.sonar.ranges() == (reach,) * 7  # the open floor
    assert min(run.ground.reflectance()) > 0.8  # white floor under the runner's sensors

    assert not near.buttons.pressed()
    near.aseba.write("button.center", (1,))  # as a finger would (the Playground keeps it)
    await _ticks(near, 0.1)
    assert near.buttons.pressed() == {"center"}
    near.aseba.write("button.center", (0,))
    await _ticks(near, 0.1)
    assert not near.buttons.pressed()

    near.leds.show("green")
    near.leds.circle((32, 0, 16, 0, 8, 0, 4, 0))
    async with asyncio.timeout(2):  # the LED program runs at 20 Hz on the robot
        while near.leds.shown() != ((0, 32, 0), (32, 0, 16, 0, 8, 0, 4, 0)):
            await near.clock.tick()

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

    async def turn() -> tuple[list[float], list[float], float]:
        """Heading (odometry) and time at each crossing of the half-plane's edge by the left
        sensor; the turn rate the wheels' measured speeds give on the way."""
        spin.drive.set_velocity(0.0, 2.0)
        seen: list[float] = []
        times: list[float] = []
        rates: list[float] = []
        was = spin.ground.reflectance()[0] < 0.5
        try:
            while len(seen) < 3 and spin.clock.now() < start + 10:
                await spin.clock.tick()
                dark = spin.ground.reflectance()[0] < 0.5
                if dark != was:
                    seen.append(spin.odometry.pose()[2])
                    times.append(spin.clock.now())
                    rates.append(spin.calibration.motion(*spin.sonar.readings.speeds)[1])  # type: ignore[union-attr]
                was = dark
        finally:
            spin.drive.stop()
        return seen, times, rates[-1] if rates else math.nan

    start = run.clock.now()
    xs, (headings, times, rate) = await asyncio.gather(straight(), turn())
    await asyncio.gather(_ticks(run, 0.1), _ticks(spin, 0.1))
    assert len(xs) == 2 and xs[1] - xs[0] == pytest.approx(STRIPES[1] - STRIPES[0], abs=0.02)
    assert len(headings) == 3 and headings[2] - headings[0] == pytest.approx(2 * math.pi, abs=0.3)
    assert rate == pytest.approx(2.0, abs=0.1)  # the turn rate reached, by the wheels
    assert 2 * math.pi / (times[2] - times[0]) == pytest.approx(2.0, rel=0.1)  # by the floor
    print(  # the figures, for docs/thymio.md (pytest -s shows them)
        f"front {[round(r, 4) for r in (r0, r1, r2, r3, r4)]} back {round(b5, 4), round(b6, 4)} "
        f"stripes {xs[1] - xs[0]:.4f} turn {headings[2] - headings[0]:.3f} rad "
        f"rate wheels {rate:.3f} floor {2 * math.pi / (times[2] - times[0]):.3f} rad/s"
    )
    for hw in (near, behind, run, spin):
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
