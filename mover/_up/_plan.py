"""From a checked team file to the processes to start: seeds, topology, command lines.

Nothing here starts anything or opens a session, so the plan of a large team (its router, its
200 command lines) is checked in unit tests. The command lines are ``python -m mover._cli
VERB ...``: this package starts the world and robot processes of other packages without
importing them.
"""

from __future__ import annotations

import hashlib
import json
import secrets
import sys
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from .._exceptions import ConfigError
from . import _hosts, _playground
from ._teamfile import MemberPlan, TeamPlan, WorldPlan

PEER_MESH_MAX = 12
"""The largest team (members, ``mover up`` itself included) that runs as a peer mesh; a larger
one gets a zenoh router, its members joining as clients. Measured: 50 idle peers burn 1.1
CPU-s/s, behind a router 17x less; the crossing point is tuned by ``bench/team.py``."""

PLAYGROUND_READY = 20.0
"""Seconds an Aseba Playground has, by default, until every robot answers on its port."""


def needs_router(members: int) -> bool:
    """Whether a team of ``members`` nodes should run behind a zenoh router (the topology rule
    of ``mover up`` and of the benchmarks)."""
    return members > PEER_MESH_MAX


@dataclass(frozen=True)
class Seeds:
    """The run seed and the two seeds derived from it (unless the file gave them)."""

    run: int
    world: int
    program: int


def derive(seed: int, what: str) -> int:
    """A seed for ``what`` drawn from the run ``seed`` (stable across Python versions)."""
    digest = hashlib.sha256(f"{seed}/{what}".encode()).digest()
    return int.from_bytes(digest[:4], "big") >> 1  # 31 bits: any world or program takes it


def seeds(plan: TeamPlan, run_seed: int | None = None) -> Seeds:
    """The seeds of a run: ``run_seed`` (the command line's), else the file's, else fresh."""
    run = run_seed if run_seed is not None else plan.seed
    if run is None:
        run = secrets.randbits(31)
    world = plan.world.seed if plan.world is not None and plan.world.seed is not None else None
    program = plan.program.seed if plan.program is not None else None
    return Seeds(
        run=run,
        world=world if world is not None else derive(run, "world"),
        program=program if program is not None else derive(run, "program"),
    )


@dataclass(frozen=True)
class ProcessPlan:
    """One process to start: its name (its log file and line prefix), its command line, whether
    its exit stops the team, and the line it prints once it serves (None: membership says)."""

    name: str
    argv: tuple[str, ...]
    required: bool
    member: bool = True  # a team member (the router is not)
    ready_line: str | None = None
    stage: int = 2  # started in this order, stopped in the reverse: router 0, world 1, members 2
    env: dict[str, str] = field(default_factory=dict)  # its own settings (across hosts)


def members(plan: TeamPlan) -> int:
    """How many nodes the team has: the world (an Aseba Playground is none), every group's
    processes and ``mover up``."""
    node = plan.world is not None and plan.world.kind != "playground"
    return len(plan.members) + node + 1


def uses_router(plan: TeamPlan) -> bool:
    """The file's topology, or for ``auto`` :func:`needs_router` of the team's size."""
    if plan.topology == "auto":
        return needs_router(members(plan))
    return plan.topology == "router"


def _cli(*args: str) -> tuple[str, ...]:
    return (sys.executable, "-m", "mover._cli", *args)


def processes(
    plan: TeamPlan, s: Seeds, run_dir: Path, *, port: int, host: str | None = None
) -> list[ProcessPlan]:
    """Every process of the team in start order: router, world, robots and workstations (of a
    team across hosts: those of ``host``, each with the settings that reach the router)."""
    if plan.hosts:
        assert host is not None
        if plan.world is not None and plan.world.kind == "playground":
            raise ConfigError("a playground world runs on one machine: no [[hosts]] with it")
        return _on_host(plan, s, run_dir, host)
    found: list[ProcessPlan] = []
    if uses_router(plan):
        found.append(
            ProcessPlan(
                "router",
                _cli("router", "--listen", f"tcp/127.0.0.1:{port}"),
                required=True,
                member=False,
                ready_line="router ",
                stage=0,
            )
        )
    if plan.world is not None and plan.world.kind == "playground":
        return found + playground_processes(plan)
    if plan.world is not None:
        argv = world_argv(plan.world, s, run_dir)
        found.append(ProcessPlan(plan.world.name, argv, plan.world.required, stage=1))
    found += [ProcessPlan(m.name, member_argv(m), m.required) for m in plan.members]
    return found


def playground_processes(plan: TeamPlan) -> list[ProcessPlan]:
    """An Aseba Playground and its Thymios: ``mover playground`` (no member: ready once it
    prints :data:`._playground.READY`, every robot answering on its port), then each robot
    with ``link`` to its port. ConfigError when ``asebaplayground`` is not installed."""
    w = plan.world
    assert w is not None and w.kind == "playground"
    _playground.installed()
    ports = _playground.ports_of(w.robots, w.ports)
    args = ["playground", str(w.file)]
    args += [f"--port={name}={port}" for name, port in ports.items() if port != w.robots[name]]
    args += ["--timeout", f"{w.timeout or PLAYGROUND_READY:g}"]
    world = ProcessPlan(
        w.name, _cli(*args), w.required, member=False, ready_line=_playground.READY, stage=1
    )
    robots = [
        replace(m, options={**m.options, "link": f"tcp:127.0.0.1:{ports[m.name]}"})
        if m.name in ports and m.hardware == "thymio"
        else m
        for m in plan.members
    ]
    return [world] + [ProcessPlan(m.name, member_argv(m), m.required) for m in robots]


def _on_host(plan: TeamPlan, s: Seeds, run_dir: Path, host: str) -> list[ProcessPlan]:
    found: list[ProcessPlan] = []
    if _hosts.router_host(plan).name == host:
        argv = _cli(*_hosts.router_args(plan))
        found.append(ProcessPlan("router", argv, True, member=False, ready_line="router ", stage=0))
    w = plan.world
    if w is not None and w.host == host:
        env = _hosts.member_env(plan, w.name)
        found.append(ProcessPlan(w.name, world_argv(w, s, run_dir), w.required, stage=1, env=env))
    for m in plan.members:
        if m.host == host:
            env = _hosts.member_env(plan, m.name)
            found.append(ProcessPlan(m.name, member_argv(m), m.required, env=env))
    return found


def world_argv(w: WorldPlan, s: Seeds, run_dir: Path) -> tuple[str, ...]:
    """``mover world`` or ``mover gridworld`` with the file's settings."""
    args = ["world" if w.kind == "continuous" else "gridworld", str(w.file), "--name", w.name]
    args += ["--seed", str(s.world)]
    if w.kind == "continuous":
        args += ["--lockstep"] if w.lockstep else ["--speed", f"{w.speed or 1.0:g}"]
        if w.record:
            args += ["--record", str(run_dir / f"{w.name}.jsonl")]
        if w.state_rate is not None:
            args += ["--state-rate", f"{w.state_rate:g}"]
        if w.control_delay:
            args += ["--control-delay", str(w.control_delay)]
    else:
        if w.layout is not None:
            args += ["--layout", json.dumps(w.layout)]
        if w.turns is not None:
            args += ["--turns", w.turns]
    if w.lockstep:
        args += ["--expect", str(w.expect or 0)]
    if w.timeout is not None:
        args += ["--timeout", f"{w.timeout:g}"]
    if w.until is not None:
        args += ["--until", w.until if isinstance(w.until, str) else f"{w.until:g}"]
    return _cli(*args)


def member_argv(m: MemberPlan) -> tuple[str, ...]:
    """``mover robot`` for one robot or workstation."""
    args = ["robot", "--name", m.name, "--kind", m.kind, "--hardware", m.hardware]
    if m.world is not None:
        args += ["--world", m.world]
    if m.spec:
        args += ["--spec", json.dumps(m.spec)]
    for key, value in m.options.items():
        args += ["--option", f"{key}={json.dumps(value)}"]
    return _cli(*args)


def resolved(plan: TeamPlan, s: Seeds, procs: list[ProcessPlan], router: bool) -> dict[str, Any]:
    """The team file as run, as JSON data: every default filled in, the seeds, the topology and
    the command lines (written to the run folder, so that a run can be told and repeated)."""
    data = asdict(plan)
    data["seeds"] = asdict(s)
    if data["world"] is not None:
        data["world"]["seed"] = s.world
    if data["program"] is not None:
        data["program"]["seed"] = s.program
        data["program"]["members"] = (
            list(plan.program.members if plan.program else ()) or plan.robots()
        )
    data["topology"] = "router" if router else "peer"
    data["processes"] = [{"name": p.name, "argv": list(p.argv)} for p in procs]
    plain: dict[str, Any] = json.loads(json.dumps(data, default=str))
    return plain
