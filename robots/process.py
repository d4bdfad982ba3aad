"""The robot process: a node, its hardware, its library, and the programs it can run.

``python -m robots --name ernst`` (or ``mover robot --name ernst``) opens a node in the team
given by the environment (``MOVER_TEAM``, ``MOVER_TEAM_KEY``, ``MOVER_CONNECT``...), connects to
its hardware through a backend chosen by name where the process is launched (the
``mover.hardware`` entry points, each a :class:`~robots.backend.HardwareBackend`: ``sim`` is the
continuous world over zenoh, ``grid`` the grid world; ``none`` is a workstation without a body),
exports the procedures its backend offers for that hardware, hosts the installed programs (the
``mover.programs`` entry points) and keeps its hardware's clock ticking while idle.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Mapping
from importlib.metadata import EntryPoint, entry_points
from typing import Any

from mover import Node, NodeConfig, ProgramHost, Team

from ._robot import Robot
from .backend import BaseHardware, H, HardwareBackend, check_options
from .hal import HardwareLost

log = logging.getLogger("robots.process")

#: The ``--hardware`` of a member without a body (a workstation): no backend, no options.
NO_HARDWARE = "none"


def hardware_backends() -> dict[str, EntryPoint]:
    """The installed hardware backends (``mover.hardware`` entry points), not loaded yet."""
    return {ep.name: ep for ep in entry_points(group="mover.hardware")}


def load_backend(
    hardware: str, options: Mapping[str, Any] | None = None
) -> HardwareBackend[Any] | None:
    """The backend named ``hardware``, its ``options`` checked; None for ``"none"``.

    Raises ValueError for an unknown backend, an entry point that is not a backend, or an
    option the backend does not take (the message names the backend's options).
    """
    if hardware == NO_HARDWARE:
        if options:
            raise ValueError(f"hardware {NO_HARDWARE!r} takes no options, got {sorted(options)}")
        return None
    backends = hardware_backends()
    if hardware not in backends:
        raise ValueError(
            f"no hardware backend {hardware!r} (installed: "
            f"{', '.join(sorted(backends)) or 'none'}; {NO_HARDWARE!r} for a workstation)"
        )
    backend = backends[hardware].load()
    if not isinstance(backend, HardwareBackend):
        raise ValueError(
            f"hardware entry point {hardware!r} ({backends[hardware].value}) is not a "
            "HardwareBackend (options, connect, procedures)"
        )
    check_options(hardware, backend, options or {})
    return backend


def installed_programs() -> dict[str, Callable[..., Any]]:
    """The installed programs (``mover.programs`` entry points), loaded."""
    found = {}
    for ep in entry_points(group="mover.programs"):
        try:
            found[ep.name] = ep.load()
        except Exception as exc:  # one broken program must not stop the robot
            log.warning("program %r is unavailable: %s", ep.name, exc)
    return found


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
    """Run one robot process until cancelled.

    ``hardware`` names a backend (``mover.hardware`` entry points) or is ``"none"``; ``options``
    go to its ``connect`` and are checked against its ``options`` before anything starts.
    """
    backend = load_backend(hardware, options)
    async with Node(name, team, kind=kind, config=config, unique=True) as node:
        if programs is None:
            programs = installed_programs()
        # Export first, so that a launcher that sees this member can start programs at once;
        # they wait until the hardware is up.
        host = ProgramHost(node, programs, robot=None, ready=backend is None)
        try:
            if backend is None:  # a workstation: a member without a body
                workstation: Robot[None] = Robot(name, None, node, kind)
                host.robot = workstation
                if ready:
                    ready()
                await asyncio.Event().wait()
                return
            await _serve(node, host, backend, kind, spec or {}, options or {}, ready)
        finally:
            await host.aclose()  # runs under way end before the node does


async def _serve(
    node: Node,
    host: ProgramHost,
    backend: HardwareBackend[H],
    kind: str,
    spec: Mapping[str, Any],
    options: Mapping[str, Any],
    ready: Callable[[], None] | None,
) -> None:
    robot: Robot[H] | None = None
    while True:
        hw = await _connect(node, backend, spec, options)
        if hw.radio is not None:
            node.radio.locator = hw.radio  # ground truth, for the range-limited broadcast only
        procedures = backend.procedures(hw)
        for proc_name, fn in procedures.items():
            node.export(fn, proc_name)
        if robot is None:
            robot = Robot(node.name, hw, node, kind)
            host.robot = robot
            host.ready.set()
            log.info("%s (%s) ready with programs %s", node.name, kind, sorted(host.programs))
            if ready:
                ready()
        else:
            robot.hw = hw  # programs started from now on drive the new body
            where = hw.radio.position() if hw.radio is not None else None
            at = f"({where[0]:.2f}, {where[1]:.2f})" if where is not None else "a place unknown"
            log.warning("%s: back in the world; its body is at %s", node.name, at)
        try:
            await _idle(hw)
        except HardwareLost as exc:
            log.warning("%s: %s; waiting for it to come back", node.name, exc)
            host.fail_all(exc)  # the runs under way end with it (their finally blocks run)


async def _connect(
    node: Node, backend: HardwareBackend[H], spec: Mapping[str, Any], options: Mapping[str, Any]
) -> H:
    """Connect to the hardware, waiting (and saying so, once a minute) while it is away."""
    waited = 0.0
    while True:
        try:
            return await backend.connect(node, node.name, spec, **options)
        except HardwareLost as exc:
            if waited % 60.0 == 0.0:
                log.warning("%s: waiting for the hardware: %s", node.name, exc)
            await asyncio.sleep(1.0)
            waited += 1.0


async def _idle(hw: BaseHardware) -> None:
    """Keep the clock going while idle (lock-step worlds wait for us), until cancelled."""
    try:
        while True:
            # Let the tasks the last readings woke set their commands first, so that a
            # program's command is never a tick late because this loop ticked before it.
            for _ in range(3):
                await asyncio.sleep(0)
            await hw.clock.tick()
    finally:
        hw.drive.stop()
        with contextlib.suppress(Exception):
            await asyncio.wait_for(hw.clock.tick(), 1.0)
