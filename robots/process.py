"""The robot process: a node, its hardware, its library, and the programs it can run.

``python -m robots --name ernst`` (or ``mover robot --name ernst``) opens a node in the team
given by the environment (``MOVER_TEAM``, ``MOVER_TEAM_KEY``, ``MOVER_CONNECT``...), connects to
its hardware through a backend chosen by name where the process is launched (the
``mover.hardware`` entry points: ``sim`` is the simulated world over zenoh; ``none`` is a
workstation without a body), exports a few procedures of its own, hosts the installed programs
(the ``mover.programs`` entry points) and keeps its hardware's clock ticking while idle.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Mapping
from importlib.metadata import entry_points
from typing import Any

from mover import Node, NodeConfig, ProgramHost, Team

from ._robot import Robot
from .hal import Hardware

log = logging.getLogger("robots.process")

HardwareFactory = Callable[..., Any]  # async (node, robot_id, spec, **options) -> Hardware


def hardware_backends() -> dict[str, Any]:
    """The installed hardware backends (``mover.hardware`` entry points), not loaded yet."""
    return {ep.name: ep for ep in entry_points(group="mover.hardware")}


def installed_programs() -> dict[str, Callable[..., Any]]:
    """The installed programs (``mover.programs`` entry points), loaded."""
    found = {}
    for ep in entry_points(group="mover.programs"):
        try:
            found[ep.name] = ep.load()
        except Exception as exc:  # one broken program must not stop the robot
            log.warning("program %r is unavailable: %s", ep.name, exc)
    return found


def _procedures(robot: Robot) -> dict[str, Callable[..., Any]]:
    hw = robot.hw

    def pose() -> list[float]:
        """The robot's dead-reckoned pose (x, y, heading)."""
        return list(hw.odometry.pose())

    def stop() -> None:
        """Stop the motors."""
        hw.drive.stop()

    def sense() -> dict[str, Any]:
        """What the robot senses now."""
        return {
            "time": hw.clock.now(),
            "pose": list(hw.odometry.pose()),
            "sonar": list(hw.sonar.ranges()) if hw.sonar else None,
            "bumper": hw.bumper.side() if hw.bumper else None,
            "camera": [[s.kind, s.id, s.status, s.range, s.bearing] for s in hw.camera.sightings()]
            if hw.camera
            else None,
        }

    return {"robot.pose": pose, "robot.stop": stop, "robot.sense": sense}


async def run_robot(
    name: str,
    *,
    team: Team,
    config: NodeConfig,
    kind: str = "robot",
    hardware: str = "sim",
    spec: dict[str, Any] | None = None,
    options: Mapping[str, Any] | None = None,
    programs: Mapping[str, Callable[..., Any]] | None = None,
    ready: Callable[[], None] | None = None,
) -> None:
    """Run one robot process until cancelled."""
    async with Node(name, team, kind=kind, config=config) as node:
        if programs is None:
            programs = installed_programs()
        # Export first, so that a launcher that sees this member can start programs at once;
        # they wait until the hardware is up.
        host = ProgramHost(node, programs, robot=None, ready=hardware == "none")
        if hardware == "none":  # a workstation: a member without a body
            host.robot = Robot(name, None, node, kind)  # type: ignore[arg-type]
            if ready:
                ready()
            await asyncio.Event().wait()
        backends = hardware_backends()
        if hardware not in backends:
            raise ValueError(
                f"no hardware backend {hardware!r} (installed: "
                f"{', '.join(sorted(backends)) or 'none'})"
            )
        hw: Hardware = await backends[hardware].load()(node, name, spec or {}, **(options or {}))
        if hw.radio is not None:
            node.radio.locator = hw.radio  # ground truth, for the range-limited broadcast only
        robot = Robot(name, hw, node, kind)
        for proc_name, fn in _procedures(robot).items():
            node.export(fn, proc_name)
        host.robot = robot
        host.ready.set()
        log.info("%s (%s) ready with programs %s", name, kind, sorted(programs))
        if ready:
            ready()
        try:
            while True:  # keep the clock going while idle (lock-step worlds wait for us)
                # Let the tasks the last readings woke set their commands first, so that a
                # program's command is never a tick late because this loop ticked before it.
                for _ in range(3):
                    await asyncio.sleep(0)
                await hw.clock.tick()
        finally:
            hw.drive.stop()
            with contextlib.suppress(Exception):
                await asyncio.wait_for(hw.clock.tick(), 1.0)
