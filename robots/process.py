"""The robot process: a node, its hardware, its library, and the programs it can run.

``python -m robots --name ernst`` (or ``mover robot --name ernst``) opens a node in the team
given by the environment (``MOVER_TEAM``, ``MOVER_TEAM_KEY``, ``MOVER_CONNECT``...), connects to
its hardware through a backend chosen by name where the process is launched (the
``mover.hardware`` entry points, each a :class:`~robots.backend.HardwareBackend`: ``sim`` is the
continuous world over zenoh, ``grid`` the grid world; ``none`` is a workstation without a body),
exports the procedures its backend offers for that hardware, and hosts the installed programs
(the ``mover.programs`` entry points).

While no run drives the hardware, the robot is idle (``async with hw.clock.idling()``, in a
task): a lock-step world neither waits for it nor ticks for it. :class:`HostClock` is the
host's :class:`mover.RunClock` over that: a run engages it when it starts (the idle task
ends, and the world waits for this robot's commands again) and releases it when the last run
on the host ends (idle again). A hardware lost while idle, or in a run, makes the process wait
for the hardware and connect again (``HostClock`` is replaced with the new hardware's).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections.abc import AsyncIterator, Callable, Iterator, Mapping
from importlib.metadata import EntryPoint, entry_points
from typing import Any

from mover import Node, NodeConfig, ProgramHost, RunClock, TeamCredentials
from mover._endpoints import join_hint
from mover._futures import failure

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


class InstalledPrograms(Mapping[str, Callable[..., Any]]):
    """The installed programs (``mover.programs`` entry points), each loaded when first asked
    for: a robot process imports the libraries of the programs it runs, not of every one."""

    def __init__(self) -> None:
        self._eps = {ep.name: ep for ep in entry_points(group="mover.programs")}
        self._loaded: dict[str, Callable[..., Any]] = {}

    def __getitem__(self, name: str) -> Callable[..., Any]:
        fn = self._loaded.get(name)
        if fn is None:
            ep = self._eps[name]  # KeyError: not installed
            try:
                fn = self._loaded[name] = ep.load()
            except Exception as exc:  # one broken program must not stop the robot
                log.warning("program %r is unavailable: %s", name, exc)
                raise KeyError(name) from None
        return fn

    def __iter__(self) -> Iterator[str]:
        return iter(self._eps)

    def __len__(self) -> int:
        return len(self._eps)


def installed_programs() -> Mapping[str, Callable[..., Any]]:
    """The installed programs (``mover.programs`` entry points), loaded as they are asked for."""
    return InstalledPrograms()


async def run_robot(
    name: str,
    *,
    team: TeamCredentials,
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
        lost: asyncio.Future[HardwareLost] = asyncio.get_running_loop().create_future()
        clock = HostClock(hw, lost)
        host.clock = clock  # runs engage it: until then the robot is idle
        clock.release()
        try:
            exc = await lost
        finally:
            await clock.aclose()
        log.warning("%s: %s; waiting for it to come back", node.name, exc)
        host.fail_all(exc)  # the runs under way end with it (their finally blocks run)


async def _connect(
    node: Node, backend: HardwareBackend[H], spec: Mapping[str, Any], options: Mapping[str, Any]
) -> H:
    """Connect to the hardware, waiting while it is away and saying so every
    :data:`WAIT_SAY_EVERY` seconds: what is missing, where this process looks (its
    ``MOVER_CONNECT``), whether it reached anyone, and what to set."""
    said: float | None = None  # when it last said so
    while True:
        try:
            return await backend.connect(node, node.name, spec, **options)
        except HardwareLost as exc:
            now = time.monotonic()
            if said is None or now - said >= WAIT_SAY_EVERY:
                said = now
                hint = join_hint(
                    team=node.team_name,
                    connect=node.config.connect,
                    linked=node.connected(),
                    awaited="the world",
                )
                log.warning("%s: waiting for the hardware: %s; %s", node.name, exc, hint)
            await asyncio.sleep(1.0)


WAIT_SAY_EVERY = 5.0
"""Seconds between two lines of a robot that waits for its hardware."""


class HostClock(RunClock):
    """A program host's run clock (``mover.RunClock``) over a robot's hardware and its idle task.

    ``now``, ``passed`` and ``hold`` are the hardware clock's. ``release()`` starts the idle task
    (``async with hw.clock.idling()``, the drive stopped first); ``engage()`` ends it and returns
    once it has left ``idling()``, i.e. once the world waits for this robot's commands. Both
    may be called by concurrent runs. A HardwareLost, idle or in a run (a tick that failed, a
    world that went away), is set on ``lost`` for the process to end the runs and reconnect;
    ``engage`` raises it.
    """

    def __init__(self, hw: BaseHardware, lost: asyncio.Future[HardwareLost]) -> None:
        self._hw = hw
        self._lost = lost
        self._task: asyncio.Task[None] | None = None
        self._stop = asyncio.Event()
        self._entered = asyncio.Event()
        self._waits = 0
        self._sentinel = asyncio.get_running_loop().create_task(self._watch())

    def now(self) -> float:
        """The hardware's time (simulated seconds, or a grid round)."""
        return float(self._hw.clock.now())

    async def passed(self, t: float) -> None:
        """Return once this robot handed in a command for a tick after time ``t``."""
        await self._hw.clock.passed(t)

    def reach(self, t: float) -> float:
        """How far past ``t`` the robot surely gets (the hardware clock's ``reach``)."""
        return float(self._hw.clock.reach(t))

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)``."""
        self._hw.clock.hold(t)

    @contextlib.asynccontextmanager
    async def idling(self) -> AsyncIterator[None]:
        """Idle for the block (a collective waiting for the others), engaged again after.

        Blocks of concurrent runs nest: the first releases, the last engages. Entering returns
        once the world has acknowledged the idle, and so has every command handed in before
        (with a control delay a command can be on its way still): a team step's members report
        only then, and the world rests at the same tick however the messages raced. Leaving
        waits for the world too."""
        self._waits += 1
        if self._waits == 1:
            self.release()
        try:
            await self._idle_entered()
            yield
        finally:
            self._waits -= 1
            if self._waits == 0:
                await self.engage()

    async def _idle_entered(self) -> None:
        """Until the idle task is inside the hardware's ``idling()`` (or has ended: the hardware
        lost, which ``engage`` raises)."""
        task = self._task
        if task is None:
            return
        entered = asyncio.ensure_future(self._entered.wait())
        try:
            await asyncio.wait({entered, task}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            entered.cancel()

    async def engage(self) -> None:
        """Stop idling; on return the world waits for this robot's commands."""
        task = self._task
        if task is not None:
            self._stop.set()
            await asyncio.wait([task])  # shared by concurrent engages
            if self._task is task:
                self._task = None
        if self._lost.done():
            raise self._lost.result()

    def release(self) -> None:
        """No run drives the hardware any more: idle again."""
        old = self._task
        if self._lost.done() or (old is not None and not self._stop.is_set()):
            return  # idle already (or the hardware is lost)
        self._stop = asyncio.Event()
        self._entered = asyncio.Event()
        self._task = asyncio.get_running_loop().create_task(
            self._idle(self._stop, self._entered, old)
        )
        self._task.add_done_callback(failure)

    async def _idle(
        self, stop: asyncio.Event, entered: asyncio.Event, after: asyncio.Task[None] | None
    ) -> None:
        if after is not None:
            await asyncio.wait([after])  # the idle task before has left idling()
        if stop.is_set():
            return
        self._hw.drive.stop()
        with contextlib.suppress(HardwareLost):  # the sentinel sees it too
            async with self._hw.clock.idling():
                entered.set()
                await stop.wait()

    async def _watch(self) -> None:
        """The sentinel: the clock's ``passed(inf)`` ends only when the hardware is lost."""
        try:
            await self._hw.clock.passed(math.inf)
        except HardwareLost as exc:
            if not self._lost.done():
                self._lost.set_result(exc)

    async def aclose(self) -> None:
        """End the idle task and the sentinel (the process is going away, or reconnecting)."""
        tasks = [t for t in (self._task, self._sentinel) if t is not None]
        self._task = None
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
