"""Team files: what ``mover up`` starts, read and checked before anything starts.

A team file is TOML with a ``[team]`` table (name, key, seed, topology), an optional
``[world]`` (a continuous or grid world process), arrays of tables ``[[robots]]`` and
``[[workstations]]`` (groups of member processes), an optional ``[program]`` to start once
everyone is a member, and optional ``[[hosts]]`` (the machines of a team across hosts, read by
:mod:`._hosts`; the world and each group then say ``host = "..."``). It is read by
:mod:`mover._tables`: every problem raises
:class:`TeamFileError` naming the file, the line and what is wrong (``teams/x.toml:12:
robots[1].count: must be from 1 to 200, got 1000``); unknown keys are refused with the known
ones as a hint; every count and size is bounded where it is read. Paths in the file are
relative to the file.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from .._exceptions import FileError
from .._keylines import Path as KeyPath
from .._tables import (
    BOOLEAN,
    MAPPING,
    NAME,
    STRING,
    Kind,
    Table,
    Wrong,
    hint,
    integer,
    number,
    read_text,
    shown,
    string,
    toml_table,
    vector,
)
from ._hosts import HostPlan, placed, read_hosts
from ._playground import PORT_CHOICES, world_robots

MAX_FILE_BYTES = 2**20
"""The largest team file read."""
MAX_PROCESSES = 200
"""The most processes one team file may start (the world included; a router is one more)."""
MAX_SEED = 2**63 - 1
"""Seeds are whole numbers from 0 to this."""
MAX_WAIT = 600.0
"""The longest readiness wait a file may ask for, in seconds."""
SUPERVISOR = "up"
"""The member name of ``mover up`` itself (a file may not give it to a process)."""

WORLD_KINDS = {"continuous": "world", "grid": "gridworld", "playground": "playground"}
HARDWARE_OF = {"continuous": "sim", "grid": "grid", "playground": "thymio"}  # kind -> backend
TOPOLOGIES = ("auto", "peer", "router")


class TeamFileError(FileError):
    """A team file is wrong: ``source``, ``line`` (None when unknown), ``where`` and ``problem``.

    ``mover up`` says it in one line and starts nothing.
    """


@dataclass(frozen=True)
class WorldPlan:
    """The world process: ``mover world`` (continuous) or ``mover gridworld`` (grid)."""

    kind: str
    file: Path
    name: str
    lockstep: bool = True
    speed: float | None = None
    timeout: float | None = None
    record: bool = False
    state_rate: float | None = None
    until: float | str | None = None
    layout: dict[str, Any] | None = None
    turns: str | None = None
    expect: int | None = None  # None: the robots of the file that join this world
    seed: int | None = None  # None: derived from the run seed
    required: bool = True
    control_delay: int = 0  # lock-step: a command for tick t applies at t + K (sim_hw._delayed)
    host: str | None = None  # None: the one host (or, across hosts, the first)
    robots: dict[str, int] = field(default_factory=dict)  # playground: name -> port in the file
    ports: str = "free"  # playground: "free" (a temporary copy of the file) or "file"


@dataclass(frozen=True)
class MemberPlan:
    """One robot or workstation process (``mover robot``); ``hardware`` "none": a workstation."""

    name: str
    kind: str
    hardware: str
    world: str | None = None
    spec: dict[str, Any] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    required: bool = False
    host: str | None = None  # None: the one host (or, across hosts, the first)


@dataclass(frozen=True)
class ProgramPlan:
    """The program started once everyone is a member."""

    name: str
    args: dict[str, Any] = field(default_factory=dict)
    members: tuple[str, ...] = ()  # () : every member with hardware
    run: str = ""  # "": the program's name
    seed: int | None = None  # None: derived from the run seed
    share: bool = False
    survivors: bool = False  # a member lost in a step does not fail the run


@dataclass(frozen=True)
class TeamPlan:
    """A team file, read and checked."""

    source: Path
    name: str
    key_file: Path | None = None
    seed: int | None = None  # None: a fresh run seed, said and written to the run folder
    topology: str = "auto"
    port: int | None = None  # None: a free port
    log_level: str | None = None
    ready_timeout: float | None = None  # None: 30 s and 2 s a process (they start on few cores)
    patience: float | None = None  # None: $MOVER_PATIENCE, else NodeConfig's (10 s)
    tls: Path | None = None  # the folder of `mover up --gen-config` (across hosts)
    hosts: tuple[HostPlan, ...] = ()  # () : one machine
    world: WorldPlan | None = None
    members: tuple[MemberPlan, ...] = ()
    program: ProgramPlan | None = None

    def robots(self) -> list[str]:
        """The members with hardware (a program's default members)."""
        return [m.name for m in self.members if m.hardware != "none"]


def load_team(path: str | Path) -> TeamPlan:
    """Read and check a team file; raises :class:`TeamFileError`."""
    path = Path(path)
    return parse_team(read_text(path, TeamFileError, most=MAX_FILE_BYTES, form="TOML"), path)


def parse_team(text: str, path: Path) -> TeamPlan:
    """Check the TOML ``text`` of the team file at ``path``; raises :class:`TeamFileError`."""
    root = toml_table(text, str(path), TeamFileError)
    root.only(("team", "world", "robots", "workstations", "program", "hosts"))
    team = root.table("team")
    if team is None:
        raise root.fail((), 'needs a [team] table (at least: name = "...")')
    plan = _team(team, path)
    hosts = read_hosts(root)
    world = root.table("world")
    wplan = _world(world, path.parent) if world is not None else None
    members = _groups(root, wplan)
    count = len(members) + (wplan is not None)
    if count > MAX_PROCESSES:
        raise root.fail((), f"starts {count} processes; at most {MAX_PROCESSES}")
    program = root.table("program")
    pplan = _program(program, members) if program is not None else None
    if wplan is not None and wplan.expect is None and wplan.lockstep:
        # every robot the file points at this world joins it, whatever its kind's backend
        expect = sum(m.hardware != "none" and m.world == wplan.name for m in members)
        wplan = replace(wplan, expect=expect)
    plan = replace(plan, world=wplan, members=tuple(members), program=pplan, hosts=hosts)
    return placed(plan, root)


def _path(base: Path, text: str) -> Path:
    """A path of the file, relative to the file's folder."""
    p = Path(text).expanduser()
    return p if p.is_absolute() else base / p


def _level(value: object) -> str:
    level = STRING.check(value)
    if level.upper() not in _LEVELS:
        raise Wrong(f"must be DEBUG, INFO, WARNING or ERROR (in any case), got {level!r}")
    return level.upper()


_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR")
_LEVEL = Kind("a log level", _level)
_SEED = integer(high=MAX_SEED)
_WAIT = number(high=MAX_WAIT)
_EXPECT = integer(high=MAX_PROCESSES)
_PATIENCE = number(low=0.1, high=3600.0, strict=False)


# -- the sections ------------------------------------------------------------------------------


def _team(t: Table, path: Path) -> TeamPlan:
    t.only(
        (
            "name",
            "key_file",
            "seed",
            "topology",
            "port",
            "log_level",
            "ready_timeout",
            "patience",
            "tls",
        )
    )
    key_file = t.option("key_file", STRING)
    tls = t.option("tls", STRING)
    level = t.option("log_level", _LEVEL)
    return TeamPlan(
        source=path,
        name=t.read("name", NAME),
        key_file=_path(path.parent, key_file) if key_file is not None else None,
        seed=t.option("seed", _SEED),
        topology=t.read("topology", string(TOPOLOGIES), "auto"),
        port=t.option("port", integer(low=1, high=65535)),
        log_level=level,
        ready_timeout=t.option("ready_timeout", _WAIT),
        patience=t.option("patience", _PATIENCE),
        tls=_path(path.parent, tls) if tls is not None else None,
    )


_CONTINUOUS = ("lockstep", "speed", "record", "state_rate", "control_delay")
_GRID = ("layout", "turns")
_COMMON = ("kind", "file", "name", "timeout", "until", "expect", "seed", "required", "host")


def _world(t: Table, base: Path) -> WorldPlan:
    kind = t.read("kind", string(tuple(WORLD_KINDS)), "continuous")
    if kind == "playground":
        return _playground(t, base)
    t.only(_COMMON + (_CONTINUOUS if kind == "continuous" else _GRID), kind=f"a {kind} world")
    file = t.read("file", Kind("the world file, relative to the team file", STRING.check))
    speed = t.option("speed", number(high=1000.0))
    lockstep = t.option("lockstep", BOOLEAN)
    if speed is not None and lockstep:
        raise t.fail("speed", "a lock-step world has no speed: drop lockstep or speed")
    until: float | str | None
    if kind == "continuous":
        until = t.option("until", number(high=1e9))
    else:
        until = t.option("until", string(("exhausted", "delivered", "explored", "never")))
    return WorldPlan(
        kind=kind,
        file=_path(base, file),
        name=t.read("name", NAME, WORLD_KINDS[kind]),
        lockstep=kind == "grid" or (lockstep if lockstep is not None else speed is None),
        speed=speed,
        timeout=t.option("timeout", _WAIT),
        record=t.read("record", BOOLEAN, False),
        state_rate=t.option("state_rate", number(high=1000.0, strict=False)),
        until=until,
        layout=t.option("layout", MAPPING),
        turns=t.option("turns", string(("together", "sequential"))),
        expect=t.option("expect", _EXPECT),
        seed=t.option("seed", _SEED),
        required=t.read("required", BOOLEAN, True),
        control_delay=t.read("control_delay", integer(low=0, high=100), 0),
        host=t.option("host", NAME),
    )


_PLAYGROUND = ("kind", "file", "name", "ports", "timeout", "required")


def _playground(t: Table, base: Path) -> WorldPlan:
    """An Aseba Playground world: not a member, not lock-step (:mod:`._playground`)."""
    t.only(_PLAYGROUND, kind="a playground world")
    file = _path(
        base, t.read("file", Kind("the world file, relative to the team file", STRING.check))
    )
    try:
        robots = world_robots(file.read_text(errors="replace"))
    except OSError as exc:
        raise t.fail("file", f"cannot read {file}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise t.fail("file", f"{file}: {exc}") from None
    return WorldPlan(
        kind="playground",
        file=file,
        name=t.read("name", NAME, WORLD_KINDS["playground"]),
        lockstep=False,
        timeout=t.option("timeout", _WAIT),
        required=t.read("required", BOOLEAN, True),
        robots=robots,
        ports=t.read("ports", string(PORT_CHOICES), "free"),
    )


def _on_playground(
    g: Table, world: WorldPlan, names: list[str], hardware: str, options: dict[str, Any]
) -> dict[str, Any]:
    """A robot group beside a playground world: Thymios of the world file, whose ``link``
    ``mover up`` gives (the group's options without it)."""
    if hardware != "thymio":
        raise g.fail("hardware", f"a playground world's robots are thymio, got {hardware!r}")
    if "link" in options:
        raise g.fail("options", "the playground world gives each robot its link: drop link")
    for i, name in enumerate(names):
        if name not in world.robots:
            known = ", ".join(world.robots)
            raise g.fail(
                ("names", i) if g.has("names") else "prefix",
                f"{name!r} is no robot of {world.file} ({known})",
            )
    return options


_GROUP = ("names", "prefix", "count", "first", "kind", "required")
_ROBOT = ("hardware", "world", "spec", "options", "poses", "placement")


def _groups(root: Table, world: WorldPlan | None) -> list[MemberPlan]:
    members: list[MemberPlan] = []
    seen: dict[str, KeyPath] = {} if world is None else {world.name: ("world", "name")}
    seen[SUPERVISOR] = ()
    for section in ("robots", "workstations"):
        for g in root.tables(section, most=MAX_PROCESSES):
            made = _group(g, world, robot=section == "robots")
            for m in made:
                if m.name in seen:
                    holder = "mover up itself" if m.name == SUPERVISOR else "another process"
                    raise g.fail((), f"the name {m.name!r} is taken by {holder}")
                seen[m.name] = g.path
            members += made
            if len(members) > MAX_PROCESSES:
                raise g.fail((), f"more than {MAX_PROCESSES} processes in the file")
    return members


def _group(g: Table, world: WorldPlan | None, *, robot: bool) -> list[MemberPlan]:
    known = (*_GROUP, *_ROBOT, "host") if robot else (*_GROUP, "host")
    g.only(known, kind="a robot group" if robot else None)
    names = _names(g)
    kind = g.read("kind", NAME, "robot" if robot else "workstation")
    required = g.read("required", BOOLEAN, False)
    host = g.option("host", NAME)
    if not robot:
        return [MemberPlan(n, kind, "none", required=required, host=host) for n in names]
    default_hw = HARDWARE_OF[world.kind] if world is not None else "sim"
    hardware = g.read("hardware", NAME, default_hw)
    spec = g.read("spec", MAPPING, {})
    options = g.read("options", MAPPING, {})
    poses = _poses(g, len(names))
    if poses and hardware != "sim":
        raise g.fail("poses" if g.has("poses") else "placement", "only sim robots have poses")
    target = g.option("world", NAME) or (world.name if world is not None else None)
    if hardware == "none":
        target = None
    if world is not None and world.kind == "playground":
        target, options = None, _on_playground(g, world, names, hardware, options)
    elif world is not None and target == world.name and hardware == "sim" and not poses:
        _in_world(g, names, world)
    return [
        MemberPlan(
            name,
            kind,
            hardware,
            world=target,
            spec={**spec, "pose": list(poses[i])} if poses else dict(spec),
            options=dict(options),
            required=required,
            host=host,
        )
        for i, name in enumerate(names)
    ]


def _in_world(g: Table, names: list[str], world: WorldPlan) -> None:
    """Each robot placed by the world is one of its file's ``[[robots]]`` (a misspelt name
    would get a default body); a world file that lists none places any name."""
    try:
        listed = tomllib.loads(world.file.read_text()).get("robots", [])
        bodies = [str(r["id"]) for r in listed if isinstance(r, dict) and "id" in r]
    except (OSError, ValueError, TypeError):
        return  # the world's own reader says what is wrong with its file
    for i, name in enumerate(names):
        if bodies and name not in bodies:
            key: str | KeyPath = ("names", i) if g.has("names") else "prefix"
            problem = f"{name!r} is not a robot of {world.file.name}{hint(name, bodies)}"
            raise g.fail(key, f"{problem}; its robots: {', '.join(bodies)}")


def _names(g: Table) -> list[str]:
    listed = g.get("names")
    if listed is not None:
        if g.has("prefix") or g.has("count"):
            raise g.fail("names", "give either names or prefix and count, not both")
        names = _listed(g, "names", listed)
    else:
        prefix = g.option("prefix", NAME)
        count = g.option("count", integer(low=1, high=MAX_PROCESSES))
        if prefix is None or count is None:
            raise g.fail((), "needs names = [...], or prefix and count")
        start = g.read("first", integer(high=10**6), 1)
        names = [g.check("prefix", f"{prefix}{start + i}", NAME) for i in range(count)]
    dup = next((n for i, n in enumerate(names) if n in names[:i]), None)
    if dup is not None:
        raise g.fail("names", f"{dup!r} is listed twice")
    return names


def _listed(t: Table, key: str, listed: object) -> list[str]:
    """A non-empty list of at most :data:`MAX_PROCESSES` names."""
    if not isinstance(listed, list) or not 0 < len(listed) <= MAX_PROCESSES:
        raise t.fail(key, f"must be a list of 1 to {MAX_PROCESSES} names, got {shown(listed)}")
    return [t.check((key, i), n, NAME) for i, n in enumerate(listed)]


_POSE = vector(3)
_STEP = vector(2)


def _poses(g: Table, n: int) -> list[tuple[float, ...]]:
    """Explicit ``poses`` (one per robot), a ``placement`` line, or none: the world places."""
    poses = g.get("poses")
    line = g.table("placement")
    if poses is not None and line is not None:
        raise g.fail("placement", "give either poses or placement, not both")
    if poses is not None:
        if not isinstance(poses, list) or len(poses) != n:
            raise g.fail("poses", f"must be a list of {n} poses [x, y, heading_degrees]")
        return [g.check(("poses", i), p, _POSE) for i, p in enumerate(poses)]
    if line is None:
        return []
    line.only(("start", "step"))
    x, y, h = line.read("start", _POSE)
    dx, dy = line.read("step", _STEP)
    return [(x + i * dx, y + i * dy, h) for i in range(n)]


def _program(t: Table, members: list[MemberPlan]) -> ProgramPlan:
    t.only(("name", "args", "members", "run", "seed", "share", "survivors"))
    name = t.read("name", NAME)
    listed = t.get("members")
    chosen: tuple[str, ...] = ()
    if listed is not None:
        known = [m.name for m in members]
        chosen = tuple(_listed(t, "members", listed))
        for i, n in enumerate(chosen):
            if n not in known:
                raise t.fail(("members", i), f"{n!r} is no member of this file{hint(n, known)}")
    elif not any(m.hardware != "none" for m in members):
        raise t.fail("members", "the file has no robot: name the members to run it on")
    return ProgramPlan(
        name=name,
        args=t.read("args", MAPPING, {}),
        members=chosen,
        run=t.read("run", NAME, name),
        seed=t.option("seed", _SEED),
        share=t.read("share", BOOLEAN, False),
        survivors=t.read("survivors", BOOLEAN, False),
    )
