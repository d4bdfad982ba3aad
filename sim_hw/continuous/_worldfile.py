"""World files (TOML or JSON) and the settings dicts robots join with.

A world file has a ``[world]`` table (``size``, ``name``, ``cell``), an optional ``[robot]`` table
of robot defaults, and arrays of tables ``[[robots]]``, ``[[obstacles]]``, ``[[boxes]]``,
``[[immovables]]``, ``[[targets]]``, ``[[resources]]``, ``[[beacons]]``, ``[[floor]]``, the
ceiling's ``[[eyebots]]`` (``id``, ``center``, ``heading``, ``view``, ``cone``), ``[[areas]]``
(``id``, ``center``, ``radius``) and ``[ceiling]`` (``omni_range``); or a
``[generator]`` table (``kind = "random_obstacles"`` or ``"double_corridor"``) that builds the
arena, to which the arrays are added. Lengths are metres, masses kilograms, forces newtons;
**angles in files are degrees**. Unknown keys are errors (a typo must not pass silently).

Every problem raises :class:`WorldFileError` naming the file, the field and what is wrong.
"""

from __future__ import annotations

import argparse
import json
import math
import tomllib
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from mover.cli import member_name

from ._generate import double_corridor, random_obstacles
from ._spec import (
    AreaSpec,
    BoxSpec,
    CameraSpec,
    EyeBotSpec,
    ImmovableSpec,
    MarkerSpec,
    ObstacleSpec,
    OdometrySpec,
    RobotSpec,
    SonarSpec,
    WorldSpec,
)

_T = TypeVar("_T")


MAX_SIDE = 1000.0
"""The longest side of an arena, in metres (a larger one is refused where it is read)."""
MAX_GENERATED = 10_000
"""The most obstacles a generator may place."""
MAX_RAYS = 360
"""The most rays a sonar may have."""
MAX_FILE_BYTES = 16 * 2**20
"""The largest world file read."""
MAX_EYEBOTS = 1000
"""The most eye-bots a world file may hang from the ceiling (and the most areas it may mark)."""


class WorldFileError(ValueError):
    """A world file (or a robot's settings) is wrong: ``source``, ``field`` and ``problem``."""

    def __init__(self, source: str, field: str, problem: str) -> None:
        self.source, self.field, self.problem = source, field, problem
        where = f"{source}: {field}" if field else source
        super().__init__(f"{where}: {problem}")


class _Table:
    """A dict being read field by field, with the path used in error messages."""

    def __init__(self, data: Any, source: str, path: str) -> None:
        if not isinstance(data, dict):
            raise WorldFileError(source, path, f"must be a table, got {_kind(data)}")
        self.data, self.source, self.path = data, source, path
        self.seen: set[str] = set()

    def field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def fail(self, key: str, problem: str) -> WorldFileError:
        return WorldFileError(self.source, self.field(key), problem)

    def get(self, key: str) -> Any:
        self.seen.add(key)
        return self.data.get(key)

    def has(self, key: str) -> bool:
        return key in self.data

    def number(
        self,
        key: str,
        default: float | None = None,
        *,
        low: float | None = 0.0,
        strict: bool = True,
    ) -> float:
        value = self.get(key)
        if value is None:
            if default is None:
                raise self.fail(key, "is required (a number)")
            return default
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not number or not math.isfinite(value):
            raise self.fail(key, f"must be a number, got {value!r}")
        if low is not None and (value <= low if strict else value < low):
            raise self.fail(key, f"must be {'>' if strict else '>='} {low:g}, got {value!r}")
        return float(value)

    def integer(
        self, key: str, default: int | None = None, *, low: int = 0, high: int | None = None
    ) -> int:
        value = self.get(key)
        if value is None:
            if default is None:
                raise self.fail(key, "is required (an integer)")
            return default
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"must be an integer, got {value!r}")
        if value < low:
            raise self.fail(key, f"must be >= {low}, got {value!r}")
        if high is not None and value > high:
            raise self.fail(key, f"must be at most {high}, got {value!r}")
        return value

    def string(self, key: str, default: str | None = None) -> str:
        value = self.get(key)
        if value is None:
            if default is None:
                raise self.fail(key, "is required (a string)")
            return default
        if not isinstance(value, str):
            raise self.fail(key, f"must be a string, got {value!r}")
        return value

    def boolean(self, key: str, default: bool) -> bool:
        value = self.get(key)
        if value is None:
            return default
        if not isinstance(value, bool):
            raise self.fail(key, f"must be true or false, got {value!r}")
        return value

    def vector(
        self,
        key: str,
        n: int,
        default: tuple[float, ...] | None = None,
        *,
        positive: bool = False,
        high: float | None = None,
    ) -> Any:
        value = self.get(key)
        if value is None:
            if default is None:
                raise self.fail(key, f"is required (a list of {n} numbers)")
            return default
        ok = (
            isinstance(value, list)
            and len(value) == n
            and all(
                isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                for v in value
            )
        )
        if not ok:
            raise self.fail(key, f"must be a list of {n} numbers, got {value!r}")
        if positive and any(v <= 0 for v in value):
            raise self.fail(key, f"must be positive, got {value!r}")
        if high is not None and any(abs(v) > high for v in value):
            raise self.fail(key, f"must be at most {high:g}, got {value!r}")
        return tuple(float(v) for v in value)

    def table(self, key: str) -> _Table | None:
        value = self.get(key)
        return None if value is None else _Table(value, self.source, self.field(key))

    def tables(self, key: str) -> list[_Table]:
        value = self.get(key)
        if value is None:
            return []
        if not isinstance(value, list):
            raise self.fail(key, f"must be an array of tables, got {_kind(value)}")
        return [_Table(v, self.source, f"{self.field(key)}[{i}]") for i, v in enumerate(value)]

    def done(self) -> None:
        extra = sorted(set(self.data) - self.seen)
        if extra:
            raise self.fail(extra[0], "unknown field")


def _kind(value: Any) -> str:
    kinds: dict[type, str] = {dict: "a table", list: "a list", str: "a string"}
    return kinds.get(type(value), repr(value))


def _robot(t: _Table, base: RobotSpec) -> RobotSpec:
    pose = None
    if t.has("pose"):
        x, y, deg = t.vector("pose", 3)
        pose = (x, y, math.radians(deg))
    spec = replace(
        base,
        pose=pose if pose is not None else base.pose,
        radius=t.number("radius", base.radius),
        mass=t.number("mass", base.mass),
        force=t.number("force", base.force),
        track=t.number("track", base.track),
        max_speed=t.number("max_speed", base.max_speed),
        max_turn=t.number("max_turn", base.max_turn),
        radio=t.boolean("radio", base.radio),
        led=t.string("led", base.led),
    )
    spec = replace(spec, sonar=_device(t, "sonar", spec.sonar, _sonar, SonarSpec()))
    spec = replace(spec, camera=_device(t, "camera", spec.camera, _camera, CameraSpec()))
    od = t.table("odometry")
    if od is not None:
        base_od = spec.odometry
        spec = replace(
            spec,
            odometry=OdometrySpec(
                trans_noise=od.number("trans_noise", base_od.trans_noise, strict=False),
                rot_noise=od.number("rot_noise", base_od.rot_noise, strict=False),
                drift=od.number("drift", base_od.drift, strict=False),
            ),
        )
        od.done()
    return spec


def _device(
    t: _Table, key: str, current: _T | None, read: Callable[[_Table, _T], _T], fresh: _T
) -> _T | None:
    value = t.data.get(key)
    if value is False:
        t.seen.add(key)
        return None
    sub = t.table(key)
    if sub is None:
        return current
    made = read(sub, current or fresh)
    sub.done()
    return made


def _sonar(t: _Table, base: SonarSpec) -> SonarSpec:
    return SonarSpec(
        rays=t.integer("rays", base.rays, low=1, high=MAX_RAYS),
        max_range=t.number("max_range", base.max_range),
        noise=t.number("noise", base.noise, strict=False),
    )


def _camera(t: _Table, base: CameraSpec) -> CameraSpec:
    fov = t.number("fov", math.degrees(base.fov))
    if fov > 360:
        raise t.fail("fov", f"must be at most 360 degrees, got {fov:g}")
    return CameraSpec(
        max_range=t.number("max_range", base.max_range),
        fov=math.radians(fov),
        occlusion=t.boolean("occlusion", base.occlusion),
    )


def parse_robot(data: Any, base: RobotSpec, source: str) -> RobotSpec:
    """Robot settings (as in a world file's ``[robot]`` table) over ``base``."""
    t = _Table(data, source, "")
    spec = _robot(t, base)
    t.done()
    return spec


def _obstacle(t: _Table) -> ObstacleSpec:
    shape = t.string("shape", "box")
    if shape == "box":
        return ObstacleSpec(
            "box",
            center=t.vector("center", 2),
            size=t.vector("size", 2, positive=True),
            angle=math.radians(t.number("angle", 0.0, low=None)),
        )
    if shape == "circle":
        return ObstacleSpec("circle", center=t.vector("center", 2), radius=t.number("radius"))
    if shape == "segment":
        return ObstacleSpec(
            "segment", a=t.vector("a", 2), b=t.vector("b", 2), radius=t.number("radius", 0.05)
        )
    raise t.fail("shape", f"must be 'box', 'circle' or 'segment', got {shape!r}")


def _box(t: _Table, default_friction: float) -> BoxSpec:
    return BoxSpec(
        id=t.string("id"),
        center=t.vector("center", 2),
        size=t.vector("size", 2, positive=True),
        mass=t.number("mass"),
        friction=t.number("friction", default_friction, strict=False),
        angle=math.radians(t.number("angle", 0.0, low=None)),
        status=t.string("status", ""),
    )


def _immovable(t: _Table) -> ImmovableSpec:
    shape = t.string("shape", "box")
    if shape not in ("box", "circle"):
        raise t.fail("shape", f"must be 'box' or 'circle', got {shape!r}")
    return ImmovableSpec(
        id=t.string("id"),
        center=t.vector("center", 2),
        shape=shape,
        size=t.vector("size", 2, (0.5, 0.5), positive=True),
        radius=t.number("radius", 0.25),
        angle=math.radians(t.number("angle", 0.0, low=None)),
        status=t.string("status", ""),
    )


def _marker(t: _Table, kind: str) -> MarkerSpec:
    status = str(t.integer("amount", 1)) if kind == "resource" else t.string("status", "")
    return MarkerSpec(
        kind,
        t.string("id"),
        t.vector("center", 2),
        t.number("radius", 0.2),
        status,
        t.number("hears", 0.0, strict=False),
    )


def _eyebot(t: _Table) -> EyeBotSpec:
    eid = t.string("id")
    try:
        member_name(eid)  # an eye-bot's id is its process's name in the team
    except argparse.ArgumentTypeError as exc:
        raise t.fail("id", str(exc)) from None
    view = t.number("view", 1.0)
    return EyeBotSpec(
        eid,
        t.vector("center", 2),
        heading=math.radians(t.number("heading", 0.0, low=None)),
        view=view,
        cone=t.number("cone", min(0.5, view)),
    )


def _area(t: _Table) -> AreaSpec:
    return AreaSpec(t.string("id"), t.vector("center", 2), t.number("radius", 1.0))


def _ceiling(top: _Table, spec: WorldSpec, source: str) -> WorldSpec:
    """The ceiling's sections: ``[ceiling]``, ``[[eyebots]]``, ``[[areas]]``."""
    omni = spec.omni_range
    ct = top.table("ceiling")
    if ct is not None:
        omni = ct.number("omni_range", omni)
        ct.done()
    eyes = [_finish(t, _eyebot(t)) for t in top.tables("eyebots")]
    if len(eyes) > MAX_EYEBOTS:
        raise WorldFileError(source, "eyebots", f"at most {MAX_EYEBOTS}, got {len(eyes)}")
    areas = [_finish(t, _area(t)) for t in top.tables("areas")]
    if len(areas) > MAX_EYEBOTS:
        raise WorldFileError(source, "areas", f"at most {MAX_EYEBOTS}, got {len(areas)}")
    for key, ids in (("eyebots", [e.id for e in eyes]), ("areas", [a.id for a in areas])):
        for i, ident in enumerate(ids):
            if ident in ids[:i] or (key == "eyebots" and ident in spec.robots):
                raise WorldFileError(source, f"{key}[{i}].id", f"{ident!r} is already used")
    return replace(
        spec,
        eyebots=spec.eyebots + tuple(eyes),
        areas=spec.areas + tuple(areas),
        omni_range=omni,
    )


def _generated(t: _Table) -> WorldSpec:
    kind = t.string("kind")
    if kind == "random_obstacles":
        spec = random_obstacles(
            size=t.vector("size", 2, (10.0, 10.0), positive=True, high=MAX_SIDE),
            count=t.integer("count", 20, high=MAX_GENERATED),
            rng=np.random.default_rng(t.integer("seed", 0)),
            min_size=t.number("min_size", 0.2),
            max_size=t.number("max_size", 0.8),
            clearance=t.number("clearance", 0.6, strict=False),
        )
    elif kind == "double_corridor":
        spec = double_corridor(
            length=t.number("length", 20.0),
            ratio=t.number("ratio", 1.0),
            width=t.number("width", 1.0),
            room=t.number("room", 3.0),
        )
    else:
        raise t.fail("kind", f"must be 'random_obstacles' or 'double_corridor', got {kind!r}")
    t.done()
    return spec


SECTIONS = {
    "world",
    "robot",
    "robots",
    "obstacles",
    "boxes",
    "immovables",
    "targets",
    "resources",
    "beacons",
    "floor",
    "generator",
    "ceiling",
    "eyebots",
    "areas",
}


def parse_world(data: Any, source: str) -> WorldSpec:
    """A :class:`WorldSpec` from the parsed content of a world file."""
    top = _Table(data, source, "")
    gen = top.table("generator")
    spec = _generated(gen) if gen is not None else WorldSpec()
    w = top.table("world")
    if w is not None:
        spec = replace(
            spec,
            size=w.vector("size", 2, spec.size, positive=True, high=MAX_SIDE),
            name=w.string("name", spec.name),
            cell=w.number("cell", spec.cell),
        )
        w.done()
    elif gen is None:
        raise WorldFileError(source, "world", "is required (a table with at least 'size')")
    base = spec.robot
    rt = top.table("robot")
    if rt is not None:
        base = _robot(rt, base)
        rt.done()
    robots: dict[str, RobotSpec] = dict(spec.robots)
    for t in top.tables("robots"):
        rid = t.string("id")
        try:
            member_name(rid)  # a robot's id is its process's name in the team
        except argparse.ArgumentTypeError as exc:
            raise t.fail("id", str(exc)) from None
        if rid in robots:
            raise t.fail("id", f"robot {rid!r} appears twice")
        robots[rid] = _robot(t, base)
        t.done()
    obstacles = list(spec.obstacles) + [_finish(t, _obstacle(t)) for t in top.tables("obstacles")]
    boxes = list(spec.boxes) + [_finish(t, _box(t, 0.5)) for t in top.tables("boxes")]
    immovables = list(spec.immovables) + [
        _finish(t, _immovable(t)) for t in top.tables("immovables")
    ]
    markers = list(spec.markers)
    for key, kind in (("targets", "target"), ("resources", "resource"), ("beacons", "beacon")):
        markers += [_finish(t, _marker(t, kind)) for t in top.tables(key)]
    floor = list(spec.floor)
    for t in top.tables("floor"):
        i, j = t.integer("cell_x"), t.integer("cell_y")
        floor.append((i, j, t.integer("value", 0, low=-(2**62)), t.string("colour", "")))
        t.done()
    spec = _ceiling(top, replace(spec, robots=robots), source)
    top.done()
    spec = replace(
        spec,
        robot=base,
        robots=robots,
        obstacles=tuple(obstacles),
        boxes=tuple(boxes),
        immovables=tuple(immovables),
        markers=tuple(markers),
        floor=tuple(floor),
    )
    _check_ids(spec, source)
    _check_inside(spec, source)
    return spec


def _finish(t: _Table, made: _T) -> _T:
    t.done()
    return made


def _check_ids(spec: WorldSpec, source: str) -> None:
    seen: dict[str, str] = {}
    things = [("boxes", b.id) for b in spec.boxes] + [("immovables", i.id) for i in spec.immovables]
    things += [(m.kind + "s", m.id) for m in spec.markers]
    counts: dict[str, int] = {}
    for section, ident in things:
        index = counts.get(section, 0)
        counts[section] = index + 1
        if ident in seen:
            raise WorldFileError(
                source, f"{section}[{index}].id", f"{ident!r} is already used in {seen[ident]}"
            )
        seen[ident] = section


def _check_inside(spec: WorldSpec, source: str) -> None:
    w, h = spec.size
    fx, fy = math.ceil(w / spec.cell), math.ceil(h / spec.cell)

    def inside(p: tuple[float, float]) -> bool:
        return 0.0 <= p[0] <= w and 0.0 <= p[1] <= h

    for i, b in enumerate(spec.boxes):
        if not inside(b.center):
            raise WorldFileError(source, f"boxes[{i}].center", f"{b.center} is outside the arena")
    for rid, r in spec.robots.items():
        if r.pose is not None and not inside(r.pose[:2]):
            raise WorldFileError(
                source, f"robots[{rid}].pose", f"{r.pose[:2]} is outside the arena"
            )
    for k, (i, j, _, _) in enumerate(spec.floor):
        if i >= fx or j >= fy:
            raise WorldFileError(
                source, f"floor[{k}]", f"cell ({i}, {j}) is outside the {fx}×{fy} floor"
            )


def load_world(path: str | Path) -> WorldSpec:
    """Read a ``.toml`` or ``.json`` world file."""
    path = Path(path)
    source = str(path)
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise WorldFileError(source, "", f"is over {MAX_FILE_BYTES // 2**20} MiB")
        raw = path.read_bytes()
    except OSError as exc:
        raise WorldFileError(source, "", f"cannot read: {exc.strerror or exc}") from None
    if path.suffix == ".toml":
        try:
            data = tomllib.loads(raw.decode("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise WorldFileError(source, "", f"not valid TOML: {exc}") from None
        except RecursionError:
            raise WorldFileError(source, "", "not valid TOML: nested too deeply") from None
    elif path.suffix == ".json":
        try:
            data = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError as exc:
            raise WorldFileError(source, "", f"not UTF-8: {exc}") from None
        except json.JSONDecodeError as exc:
            raise WorldFileError(
                source, f"line {exc.lineno}", f"not valid JSON: {exc.msg} (column {exc.colno})"
            ) from None
        except RecursionError:
            raise WorldFileError(source, "", "not valid JSON: nested too deeply") from None
    else:
        raise WorldFileError(source, "", "must end in .toml or .json")
    return parse_world(data, source)
