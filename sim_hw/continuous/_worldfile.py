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

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TypeVar

import numpy as np

from mover import FileError
from mover._tables import (
    BOOLEAN,
    NAME,
    STRING,
    Source,
    Table,
    integer,
    json_table,
    number,
    pair,
    read_text,
    string,
    toml_table,
    vector,
)

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
MAX_THINGS = 100_000
"""The most entries of any other array of tables (robots, obstacles, boxes, floor cells...)."""
MAX_SEED = 2**63 - 1
"""A generator's seed is a whole number from 0 to this."""
MAX_COUNT = 10**9
"""The largest resource amount, floor cell index or floor value magnitude."""
MAX_FLOOR_CELLS = 2**24
"""The most floor cells an arena may have (8 bytes each: a 1000 m square at the default 0.25 m)."""


class WorldFileError(FileError):
    """A world file (or a robot's settings) is wrong: ``source``, ``line``, ``where``, ``problem``.

    ``field`` is ``where`` under its older name. The world refuses to start; a joining robot's
    wrong settings come back to it as this error.
    """

    @property
    def field(self) -> str:
        """The key that is wrong (``boxes[1].mass``), or "" for the file as a whole."""
        return self.where


_POSITIVE = number()
_NONNEGATIVE = number(strict=False)
_ANGLE = number(low=None)  # degrees, either sign
_POINT = pair()
_POSE = vector(3)
_EXTENT = pair(low=0.0)  # a size: both sides > 0
_SIDES = pair(low=0.0, high=MAX_SIDE)  # an arena's size


def _robot(t: Table, base: RobotSpec) -> RobotSpec:
    pose = None
    written = t.option("pose", _POSE)
    if written is not None:
        x, y, deg = written
        pose = (x, y, math.radians(deg))
    spec = replace(
        base,
        pose=pose if pose is not None else base.pose,
        radius=t.read("radius", _POSITIVE, base.radius),
        mass=t.read("mass", _POSITIVE, base.mass),
        force=t.read("force", _POSITIVE, base.force),
        track=t.read("track", _POSITIVE, base.track),
        max_speed=t.read("max_speed", _POSITIVE, base.max_speed),
        max_turn=t.read("max_turn", _POSITIVE, base.max_turn),
        radio=t.read("radio", BOOLEAN, base.radio),
        led=t.read("led", STRING, base.led),
    )
    spec = replace(spec, sonar=_device(t, "sonar", spec.sonar, _sonar, SonarSpec()))
    spec = replace(spec, camera=_device(t, "camera", spec.camera, _camera, CameraSpec()))
    od = t.table("odometry")
    if od is not None:
        base_od = spec.odometry
        spec = replace(
            spec,
            odometry=OdometrySpec(
                trans_noise=od.read("trans_noise", _NONNEGATIVE, base_od.trans_noise),
                rot_noise=od.read("rot_noise", _NONNEGATIVE, base_od.rot_noise),
                drift=od.read("drift", _NONNEGATIVE, base_od.drift),
            ),
        )
        od.done()
    return spec


def _device(
    t: Table, key: str, current: _T | None, read: Callable[[Table, _T], _T], fresh: _T
) -> _T | None:
    if t.data.get(key) is False:  # the robot has none
        t.get(key)
        return None
    sub = t.table(key)
    if sub is None:
        return current
    return _finish(sub, read(sub, current or fresh))


def _sonar(t: Table, base: SonarSpec) -> SonarSpec:
    return SonarSpec(
        rays=t.read("rays", integer(low=1, high=MAX_RAYS), base.rays),
        max_range=t.read("max_range", _POSITIVE, base.max_range),
        noise=t.read("noise", _NONNEGATIVE, base.noise),
    )


def _camera(t: Table, base: CameraSpec) -> CameraSpec:
    return CameraSpec(
        max_range=t.read("max_range", _POSITIVE, base.max_range),
        fov=math.radians(t.read("fov", number(high=360.0), math.degrees(base.fov))),
        occlusion=t.read("occlusion", BOOLEAN, base.occlusion),
    )


def parse_robot(data: object, base: RobotSpec, source: str) -> RobotSpec:
    """Robot settings (as in a world file's ``[robot]`` table) over ``base``."""
    t = Table(data, Source(source, WorldFileError))
    return _finish(t, _robot(t, base))


def _obstacle(t: Table) -> ObstacleSpec:
    shape = t.read("shape", string(("box", "circle", "segment")), "box")
    if shape == "box":
        return ObstacleSpec(
            "box",
            center=t.read("center", _POINT),
            size=t.read("size", _EXTENT),
            angle=math.radians(t.read("angle", _ANGLE, 0.0)),
        )
    if shape == "circle":
        return ObstacleSpec(
            "circle", center=t.read("center", _POINT), radius=t.read("radius", _POSITIVE)
        )
    return ObstacleSpec(
        "segment",
        a=t.read("a", _POINT),
        b=t.read("b", _POINT),
        radius=t.read("radius", _POSITIVE, 0.05),
    )


def _box(t: Table, default_friction: float) -> BoxSpec:
    return BoxSpec(
        id=t.read("id", STRING),
        center=t.read("center", _POINT),
        size=t.read("size", _EXTENT),
        mass=t.read("mass", _POSITIVE),
        friction=t.read("friction", _NONNEGATIVE, default_friction),
        angle=math.radians(t.read("angle", _ANGLE, 0.0)),
        status=t.read("status", STRING, ""),
    )


def _immovable(t: Table) -> ImmovableSpec:
    return ImmovableSpec(
        id=t.read("id", STRING),
        center=t.read("center", _POINT),
        shape=t.read("shape", string(("box", "circle")), "box"),
        size=t.read("size", _EXTENT, (0.5, 0.5)),
        radius=t.read("radius", _POSITIVE, 0.25),
        angle=math.radians(t.read("angle", _ANGLE, 0.0)),
        status=t.read("status", STRING, ""),
    )


def _marker(t: Table, kind: str) -> MarkerSpec:
    if kind == "resource":
        status = str(t.read("amount", integer(high=MAX_COUNT), 1))
    else:
        status = t.read("status", STRING, "")
    return MarkerSpec(
        kind,
        t.read("id", STRING),
        t.read("center", _POINT),
        t.read("radius", _POSITIVE, 0.2),
        status,
        t.read("hears", _NONNEGATIVE, 0.0),
    )


def _eyebot(t: Table) -> EyeBotSpec:
    eid = t.read("id", NAME)  # an eye-bot's id is its process's name in the team
    view = t.read("view", _POSITIVE, 1.0)
    return EyeBotSpec(
        eid,
        t.read("center", _POINT),
        heading=math.radians(t.read("heading", _ANGLE, 0.0)),
        view=view,
        cone=t.read("cone", _POSITIVE, min(0.5, view)),
    )


def _area(t: Table) -> AreaSpec:
    return AreaSpec(
        t.read("id", STRING), t.read("center", _POINT), t.read("radius", _POSITIVE, 1.0)
    )


def _ceiling(top: Table, spec: WorldSpec) -> WorldSpec:
    """The ceiling's sections: ``[ceiling]``, ``[[eyebots]]``, ``[[areas]]``."""
    omni = spec.omni_range
    ct = top.table("ceiling")
    if ct is not None:
        omni = _finish(ct, ct.read("omni_range", _POSITIVE, omni))
    eyes = [_finish(t, _eyebot(t)) for t in top.tables("eyebots", most=MAX_EYEBOTS)]
    areas = [_finish(t, _area(t)) for t in top.tables("areas", most=MAX_EYEBOTS)]
    for key, ids in (("eyebots", [e.id for e in eyes]), ("areas", [a.id for a in areas])):
        for i, ident in enumerate(ids):
            if ident in ids[:i] or (key == "eyebots" and ident in spec.robots):
                raise top.fail((key, i, "id"), f"{ident!r} is already used")
    return replace(
        spec,
        eyebots=spec.eyebots + tuple(eyes),
        areas=spec.areas + tuple(areas),
        omni_range=omni,
    )


def _generated(t: Table) -> WorldSpec:
    kind = t.read("kind", string(("random_obstacles", "double_corridor")))
    if kind == "random_obstacles":
        spec = random_obstacles(
            size=t.read("size", _SIDES, (10.0, 10.0)),
            count=t.read("count", integer(high=MAX_GENERATED), 20),
            rng=np.random.default_rng(t.read("seed", integer(high=MAX_SEED), 0)),
            min_size=t.read("min_size", _POSITIVE, 0.2),
            max_size=t.read("max_size", _POSITIVE, 0.8),
            clearance=t.read("clearance", _NONNEGATIVE, 0.6),
        )
    else:
        spec = double_corridor(
            length=t.read("length", _POSITIVE, 20.0),
            ratio=t.read("ratio", _POSITIVE, 1.0),
            width=t.read("width", _POSITIVE, 1.0),
            room=t.read("room", _POSITIVE, 3.0),
        )
    return _finish(t, spec)


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


def parse_world(data: object, source: str) -> WorldSpec:
    """A :class:`WorldSpec` from the parsed content of a world file."""
    return _world(Table(data, Source(source, WorldFileError)))


def _world(top: Table) -> WorldSpec:
    gen = top.table("generator")
    spec = _generated(gen) if gen is not None else WorldSpec()
    w = top.table("world")
    if w is not None:
        spec = replace(
            spec,
            size=w.read("size", _SIDES, spec.size),
            name=w.read("name", STRING, spec.name),
            cell=w.read("cell", _POSITIVE, spec.cell),
        )
        floor_cells = (spec.size[0] / spec.cell + 1) * (spec.size[1] / spec.cell + 1)
        if floor_cells > MAX_FLOOR_CELLS:
            raise w.fail(
                "cell",
                f"{spec.cell:g} m makes {floor_cells:.3g} floor cells, over {MAX_FLOOR_CELLS}",
            )
        w.done()
    elif gen is None:
        raise top.fail("world", "is required (a table with at least 'size')")
    base = spec.robot
    rt = top.table("robot")
    if rt is not None:
        base = _finish(rt, _robot(rt, base))
    robots: dict[str, RobotSpec] = dict(spec.robots)
    for t in top.tables("robots", most=MAX_THINGS):
        rid = t.read("id", NAME)  # a robot's id is its process's name in the team
        if rid in robots:
            raise t.fail("id", f"robot {rid!r} appears twice")
        robots[rid] = _finish(t, _robot(t, base))
        _inside(t, "pose", robots[rid].pose, spec.size)

    def things(key: str) -> list[Table]:
        return top.tables(key, most=MAX_THINGS)

    obstacles = list(spec.obstacles) + [_finish(t, _obstacle(t)) for t in things("obstacles")]
    boxes = list(spec.boxes)
    for t in things("boxes"):
        boxes.append(_finish(t, _box(t, 0.5)))
        _inside(t, "center", boxes[-1].center, spec.size)
    immovables = list(spec.immovables) + [_finish(t, _immovable(t)) for t in things("immovables")]
    markers = list(spec.markers)
    for key, kind in (("targets", "target"), ("resources", "resource"), ("beacons", "beacon")):
        markers += [_finish(t, _marker(t, kind)) for t in things(key)]
    floor = list(spec.floor)
    w_, h_ = spec.size
    fx, fy = math.ceil(w_ / spec.cell), math.ceil(h_ / spec.cell)
    cells = integer(high=MAX_COUNT)
    for t in things("floor"):
        i, j = t.read("cell_x", cells), t.read("cell_y", cells)
        value = t.read("value", integer(low=-MAX_COUNT, high=MAX_COUNT), 0)
        floor.append((i, j, value, t.read("colour", STRING, "")))
        t.done()
        if i >= fx or j >= fy:
            raise t.fail((), f"cell ({i}, {j}) is outside the {fx}×{fy} floor")
    spec = _ceiling(top, replace(spec, robots=robots))
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
    _check_ids(spec, top)
    return spec


def _finish(t: Table, made: _T) -> _T:
    t.done()
    return made


def _inside(t: Table, key: str, point: tuple[float, ...] | None, size: tuple[float, float]) -> None:
    """Refuse a robot's pose or a box's center outside the arena."""
    if point is not None and not (0.0 <= point[0] <= size[0] and 0.0 <= point[1] <= size[1]):
        raise t.fail(key, f"{point[:2]} is outside the arena")


def _check_ids(spec: WorldSpec, top: Table) -> None:
    seen: dict[str, str] = {}
    things = [("boxes", b.id) for b in spec.boxes] + [("immovables", i.id) for i in spec.immovables]
    things += [(m.kind + "s", m.id) for m in spec.markers]
    counts: dict[str, int] = {}
    for section, ident in things:
        index = counts.get(section, 0)
        counts[section] = index + 1
        if ident in seen:
            raise top.fail((section, index, "id"), f"{ident!r} is already used in {seen[ident]}")
        seen[ident] = section


def load_world(path: str | Path) -> WorldSpec:
    """Read a ``.toml`` or ``.json`` world file."""
    path = Path(path)
    form = {".toml": "TOML", ".json": "JSON"}.get(path.suffix, "")
    text = read_text(path, WorldFileError, most=MAX_FILE_BYTES, form=form)
    if form == "TOML":
        return _world(toml_table(text, str(path), WorldFileError))
    if form == "JSON":
        return _world(json_table(text, str(path), WorldFileError))
    raise WorldFileError(str(path), "", "must end in .toml or .json")
