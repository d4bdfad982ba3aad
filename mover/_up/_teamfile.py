"""Team files: what ``mover up`` starts, read and checked before anything starts.

A team file is TOML with a ``[team]`` table (name, key, seed, topology), an optional
``[world]`` (a continuous or grid world process), arrays of tables ``[[robots]]`` and
``[[workstations]]`` (groups of member processes) and an optional ``[program]`` to start once
everyone is a member. Every problem raises :class:`TeamFileError` naming the file, the line
and what is wrong (``teams/x.toml:12: robots[1].count: must be at most 200, got 1000``);
unknown keys are refused with the known ones as a hint; every count and size is bounded here,
where it is read. Paths in the file are relative to the file.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from .._keys import check_name
from ._lines import KeyLines
from ._lines import Path as KeyPath

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

WORLD_KINDS = {"continuous": "world", "grid": "gridworld"}  # kind -> default node name
HARDWARE_OF = {"continuous": "sim", "grid": "grid"}  # the backend that joins each kind
TOPOLOGIES = ("auto", "peer", "router")


class TeamFileError(ValueError):
    """A team file is wrong: ``source``, ``line`` (None when unknown) and ``problem``."""

    def __init__(self, source: str, line: int | None, problem: str) -> None:
        self.source, self.line, self.problem = source, line, problem
        where = f"{source}:{line}" if line is not None else source
        super().__init__(f"{where}: {problem}")


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
    world: WorldPlan | None = None
    members: tuple[MemberPlan, ...] = ()
    program: ProgramPlan | None = None

    def robots(self) -> list[str]:
        """The members with hardware (a program's default members)."""
        return [m.name for m in self.members if m.hardware != "none"]


def load_team(path: str | Path) -> TeamPlan:
    """Read and check a team file; raises :class:`TeamFileError`."""
    path = Path(path)
    source = str(path)
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise TeamFileError(source, None, f"is over {MAX_FILE_BYTES // 2**20} MiB")
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise TeamFileError(source, None, f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise TeamFileError(source, None, "is not UTF-8 text") from None
    return parse_team(text, path)


def parse_team(text: str, path: Path) -> TeamPlan:
    """Check the TOML ``text`` of the team file at ``path``; raises :class:`TeamFileError`."""
    source = str(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        found = re.search(r"at line (\d+)", str(exc))
        line = int(found.group(1)) if found else None
        raise TeamFileError(source, line, f"not valid TOML: {exc}") from None
    except RecursionError:
        raise TeamFileError(source, None, "not valid TOML: nested too deeply") from None
    root = _Table(data, (), _Context(source, KeyLines(text), path.parent))
    root.only(("team", "world", "robots", "workstations", "program"))
    team = root.table("team")
    if team is None:
        raise root.fail((), 'needs a [team] table (at least: name = "...")')
    plan = _team(team, path)
    world = root.table("world")
    wplan = _world(world) if world is not None else None
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
    return replace(plan, world=wplan, members=tuple(members), program=pplan)


# -- the sections ------------------------------------------------------------------------------


def _team(t: _Table, path: Path) -> TeamPlan:
    t.only(("name", "key_file", "seed", "topology", "port", "log_level", "ready_timeout"))
    key_file = t.string("key_file")
    level = t.string("log_level")
    if level is not None and level.upper() not in ("DEBUG", "INFO", "WARNING", "ERROR"):
        raise t.fail(("log_level",), f"must be DEBUG, INFO, WARNING or ERROR, got {level!r}")
    return TeamPlan(
        source=path,
        name=t.name("name", required=True) or "",
        key_file=t.ctx.path(key_file) if key_file is not None else None,
        seed=t.integer("seed", high=MAX_SEED),
        topology=t.choice("topology", TOPOLOGIES) or "auto",
        port=t.integer("port", low=1, high=65535),
        log_level=level.upper() if level else None,
        ready_timeout=t.number("ready_timeout", high=MAX_WAIT),
    )


_CONTINUOUS = ("lockstep", "speed", "record", "state_rate")
_GRID = ("layout", "turns")
_COMMON = ("kind", "file", "name", "timeout", "until", "expect", "seed", "required")


def _world(t: _Table) -> WorldPlan:
    kind = t.choice("kind", tuple(WORLD_KINDS)) or "continuous"
    t.only(_COMMON + (_CONTINUOUS if kind == "continuous" else _GRID), kind=f"a {kind} world")
    file = t.string("file")
    if file is None:
        raise t.fail(("file",), "is required (the world file, relative to the team file)")
    speed = t.number("speed", high=1000.0)
    lockstep = t.boolean("lockstep")
    if speed is not None and lockstep:
        raise t.fail(("speed",), "a lock-step world has no speed: drop lockstep or speed")
    until: float | str | None
    if kind == "continuous":
        until = t.number("until", high=1e9)
    else:
        until = t.choice("until", ("exhausted", "delivered", "explored", "never"))
    return WorldPlan(
        kind=kind,
        file=t.ctx.path(file),
        name=t.name("name") or WORLD_KINDS[kind],
        lockstep=kind == "grid" or (lockstep if lockstep is not None else speed is None),
        speed=speed,
        timeout=t.number("timeout", high=MAX_WAIT),
        record=bool(t.boolean("record")),
        state_rate=t.number("state_rate", high=1000.0, zero=True),
        until=until,
        layout=t.mapping("layout"),
        turns=t.choice("turns", ("together", "sequential")),
        expect=t.integer("expect", high=MAX_PROCESSES),
        seed=t.integer("seed", high=MAX_SEED),
        required=t.boolean("required") is not False,
    )


_GROUP = ("names", "prefix", "count", "first", "kind", "required")
_ROBOT = ("hardware", "world", "spec", "options", "poses", "placement")


def _groups(root: _Table, world: WorldPlan | None) -> list[MemberPlan]:
    members: list[MemberPlan] = []
    seen: dict[str, KeyPath] = {} if world is None else {world.name: ("world", "name")}
    seen[SUPERVISOR] = ()
    for section in ("robots", "workstations"):
        for g in root.tables(section):
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


def _group(g: _Table, world: WorldPlan | None, *, robot: bool) -> list[MemberPlan]:
    g.only(_GROUP + _ROBOT if robot else _GROUP, kind="a robot group" if robot else None)
    names = _names(g)
    kind = g.name("kind") or ("robot" if robot else "workstation")
    required = bool(g.boolean("required"))
    if not robot:
        return [MemberPlan(n, kind, "none", required=required) for n in names]
    default_hw = HARDWARE_OF[world.kind] if world is not None else "sim"
    hardware = g.name("hardware") or default_hw
    spec = g.mapping("spec") or {}
    options = g.mapping("options") or {}
    poses = _poses(g, len(names))
    if poses and hardware != "sim":
        raise g.fail(("poses" if g.has("poses") else "placement",), "only sim robots have poses")
    target = g.name("world") or (world.name if world is not None else None)
    if hardware == "none":
        target = None
    return [
        MemberPlan(
            name,
            kind,
            hardware,
            world=target,
            spec={**spec, "pose": list(poses[i])} if poses else dict(spec),
            options=dict(options),
            required=required,
        )
        for i, name in enumerate(names)
    ]


def _names(g: _Table) -> list[str]:
    listed = g.get("names")
    if listed is not None:
        if g.has("prefix") or g.has("count"):
            raise g.fail(("names",), "give either names or prefix and count, not both")
        if not isinstance(listed, list) or not listed:
            raise g.fail(("names",), f"must be a non-empty list of names, got {listed!r}")
        if len(listed) > MAX_PROCESSES:
            raise g.fail(("names",), f"at most {MAX_PROCESSES} names, got {len(listed)}")
        names = [g.checked_name(("names", i), n) for i, n in enumerate(listed)]
    else:
        prefix = g.name("prefix")
        count = g.integer("count", low=1, high=MAX_PROCESSES)
        if prefix is None or count is None:
            raise g.fail((), "needs names = [...], or prefix and count")
        first = g.integer("first", high=10**6)
        start = 1 if first is None else first
        names = [g.checked_name(("prefix",), f"{prefix}{start + i}") for i in range(count)]
    dup = next((n for i, n in enumerate(names) if n in names[:i]), None)
    if dup is not None:
        raise g.fail(("names",), f"{dup!r} is listed twice")
    return names


def _poses(g: _Table, n: int) -> list[tuple[float, float, float]]:
    """Explicit ``poses`` (one per robot), a ``placement`` line, or none: the world places."""
    poses = g.get("poses")
    line = g.table("placement")
    if poses is not None and line is not None:
        raise g.fail(("placement",), "give either poses or placement, not both")
    if poses is not None:
        if not isinstance(poses, list) or len(poses) != n:
            raise g.fail(("poses",), f"must be a list of {n} poses [x, y, heading_degrees]")
        return [g.vector(("poses", i), p, 3) for i, p in enumerate(poses)]
    if line is None:
        return []
    line.only(("start", "step"))
    x, y, h = line.vector(("start",), line.get("start"), 3)
    dx, dy = line.vector(("step",), line.get("step"), 2)
    return [(x + i * dx, y + i * dy, h) for i in range(n)]


def _program(t: _Table, members: list[MemberPlan]) -> ProgramPlan:
    t.only(("name", "args", "members", "run", "seed", "share", "survivors"))
    name = t.name("name", required=True) or ""
    listed = t.get("members")
    chosen: tuple[str, ...] = ()
    if listed is not None:
        if not isinstance(listed, list) or not listed:
            raise t.fail(("members",), f"must be a non-empty list of names, got {listed!r}")
        known = {m.name for m in members}
        for i, n in enumerate(listed):
            if n not in known:
                raise t.fail(("members", i), f"{n!r} is no member of this file{_hint(n, known)}")
        chosen = tuple(listed)
    elif not any(m.hardware != "none" for m in members):
        raise t.fail(("members",), "the file has no robot: name the members to run it on")
    return ProgramPlan(
        name=name,
        args=t.mapping("args") or {},
        members=chosen,
        run=t.name("run") or name,
        seed=t.integer("seed", high=MAX_SEED),
        share=bool(t.boolean("share")),
        survivors=bool(t.boolean("survivors")),
    )


# -- reading fields ----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Context:
    source: str
    lines: KeyLines
    base: Path  # the team file's folder

    def path(self, text: str) -> Path:
        p = Path(text).expanduser()
        return p if p.is_absolute() else self.base / p


class _Table:
    """A table being read key by key; every error names its line."""

    def __init__(self, data: Any, path: KeyPath, ctx: _Context) -> None:
        self.data, self.path, self.ctx = data, path, ctx
        if not isinstance(data, dict):
            raise self.fail((), f"must be a table, got {_kind(data)}")

    def fail(self, key: KeyPath, problem: str) -> TeamFileError:
        full = (*self.path, *key)
        where = ".".join(str(p) if isinstance(p, str) else f"[{p}]" for p in full)
        where = where.replace(".[", "[")
        line = self.ctx.lines.line(full)
        return TeamFileError(self.ctx.source, line, f"{where}: {problem}" if where else problem)

    def only(self, known: Iterable[str], *, kind: str | None = None) -> None:
        known = tuple(known)
        for key in self.data:
            if key not in known:
                what = f" in {kind}" if kind else ""
                raise self.fail(
                    (key,), f"unknown key{what}{_hint(key, known)}; known: {', '.join(known)}"
                )

    def has(self, key: str) -> bool:
        return key in self.data

    def get(self, key: str) -> Any:
        return self.data.get(key)

    def string(self, key: str) -> str | None:
        value = self.get(key)
        if value is not None and not isinstance(value, str):
            raise self.fail((key,), f"must be a string, got {_kind(value)}")
        return value

    def name(self, key: str, *, required: bool = False) -> str | None:
        value = self.string(key)
        if value is None:
            if required:
                raise self.fail((key,), "is required (a name)")
            return None
        return self.checked_name((key,), value)

    def checked_name(self, key: KeyPath, value: Any) -> str:
        if not isinstance(value, str):
            raise self.fail(key, f"must be a name (a string), got {_kind(value)}")
        try:
            return check_name("member", value)
        except ValueError as exc:
            raise self.fail(key, str(exc)) from None

    def choice(self, key: str, choices: tuple[str, ...]) -> str | None:
        value = self.string(key)
        if value is not None and value not in choices:
            raise self.fail((key,), f"must be one of {', '.join(choices)}, got {value!r}")
        return value

    def boolean(self, key: str) -> bool | None:
        value = self.get(key)
        if value is not None and not isinstance(value, bool):
            raise self.fail((key,), f"must be true or false, got {_kind(value)}")
        return value

    def integer(self, key: str, *, low: int = 0, high: int) -> int | None:
        value = self.get(key)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail((key,), f"must be a whole number, got {_kind(value)}")
        if not low <= value <= high:
            raise self.fail((key,), f"must be from {low} to {high}, got {value}")
        return value

    def number(self, key: str, *, high: float, zero: bool = False) -> float | None:
        value = self.get(key)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail((key,), f"must be a number, got {_kind(value)}")
        if not (value >= 0 if zero else value > 0) or not value <= high:
            low = ">= 0" if zero else "> 0"
            raise self.fail((key,), f"must be {low} and at most {high:g}, got {value}")
        return float(value)

    def vector(self, key: KeyPath, value: Any, n: int) -> Any:
        ok = isinstance(value, list) and len(value) == n
        ok = ok and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        if ok and all(math.isfinite(v) and abs(v) <= 1e6 for v in value):
            return tuple(float(v) for v in value)
        raise self.fail(key, f"must be a list of {n} numbers, got {value!r}")

    def mapping(self, key: str) -> dict[str, Any] | None:
        value = self.get(key)
        if value is not None and not isinstance(value, dict):
            raise self.fail((key,), f"must be a table, got {_kind(value)}")
        return value

    def table(self, key: str) -> _Table | None:
        value = self.get(key)
        return None if value is None else _Table(value, (*self.path, key), self.ctx)

    def tables(self, key: str) -> list[_Table]:
        value = self.get(key)
        if value is None:
            return []
        if not isinstance(value, list):
            raise self.fail((key,), f"must be an array of tables ([[{key}]]), got {_kind(value)}")
        return [_Table(v, (*self.path, key, i), self.ctx) for i, v in enumerate(value)]


def _hint(word: str, known: Iterable[str]) -> str:
    close = difflib.get_close_matches(str(word), list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _kind(value: Any) -> str:
    kinds: dict[type, str] = {dict: "a table", list: "a list", str: "a string"}
    return kinds.get(type(value), repr(value))
