"""Simulated sensors: sonar, bumper, camera, odometry, and the floor of writable cells.

Each function reads the pymunk space after a control tick and returns plain values (lists,
floats, strings) that go into a robot's readings unchanged, in process or over the wire.
Noise comes from the robot's own seeded generator, so readings do not depend on which other
robots exist or in which order they joined.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pymunk
import pymunk.batch
from pymunk._chipmunk import ffi as _ffi
from pymunk._chipmunk import lib as _lib

from robots.hal import BumperSide

from ._bodies import CAT_BOX, CAT_IMMOVABLE, CAT_MARKER, CAT_QUERY, CAT_ROBOT, CAT_WALL, SOLID

_INFO = _ffi.new("cpSegmentQueryInfo *")


def wrap(angle: float) -> float:
    """``angle`` folded into (-π, π]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi


@dataclass(slots=True)
class Entity:
    """Something a camera can name: kind, id, and how to find its centre and status."""

    kind: str
    id: str
    center: Callable[[], tuple[float, float]]
    status: Callable[[], str]
    body: pymunk.Body | None = None
    """The dynamic body, for things that can move."""


def sonar_ranges(
    space: pymunk.Space,
    pose: tuple[float, float, float],
    radius: float,
    group: int,
    angles: tuple[float, ...],
    max_range: float,
    noise: float,
    rng: np.random.Generator,
) -> list[float]:
    """Range from the rim along each ray to the first solid shape, ``max_range`` if none.

    Calls chipmunk's segment query directly (docs/physics.md: ~1 µs a ray instead of ~4 µs
    through ``Space.segment_query_first``, which builds Python objects for every hit).
    """
    x, y, heading = pose
    owner = _ffi.new("cpShapeFilter *", (group, CAT_QUERY, SOLID))
    query = owner[0]  # one struct for every ray: a tuple is converted anew on each call
    out = []
    info = _INFO
    null = _ffi.NULL
    cspace = space._space
    first = _lib.cpSpaceSegmentQueryFirst
    cos, sin = math.cos, math.sin
    for a in angles:
        c, s = cos(heading + a), sin(heading + a)
        start = (x + c * radius, y + s * radius)
        end = (x + c * (radius + max_range), y + s * (radius + max_range))
        if first(cspace, start, end, 0.0, query, info) == null:
            out.append(max_range)
            continue
        r = info.alpha * max_range
        if noise > 0.0:
            r = min(max(r + float(rng.normal(0.0, noise)), 0.0), max_range)
        out.append(r)
    return out


class Contacts:
    """Every body's contact normals after a physics step, read from chipmunk in one call.

    What ``Body.each_arbiter`` gives a body, for all bodies at once (``pymunk.batch``): the
    space's cached arbiters with contacts, each seen from both of its bodies (the normal from
    the first body to the second, negated for the second). ``each_arbiter`` cost ~4 µs a robot
    a tick even with no contact (a callback object made and called through cffi); this costs
    one call and a few µs an arbiter. A cached arbiter without contacts (shapes that parted
    within chipmunk's persistence, a sensor's, an ignored one) is in no body's list, as in
    ``each_arbiter``'s.
    """

    _FIELDS = (
        pymunk.batch.ArbiterFields.BODY_A_ID
        | pymunk.batch.ArbiterFields.BODY_B_ID
        | pymunk.batch.ArbiterFields.CONTACT_COUNT
        | pymunk.batch.ArbiterFields.NORMAL
    )

    def __init__(self) -> None:
        self._buffer = pymunk.batch.Buffer()

    def read(self, space: pymunk.Space) -> dict[int, list[tuple[float, float]]]:
        """Body id -> the normals of its contacts (from it towards what it touches)."""
        buffer = self._buffer
        buffer.clear()
        pymunk.batch.get_space_arbiters(space, self._FIELDS, buffer)
        ints = np.frombuffer(buffer.int_buf(), np.uintp).tolist()  # a, b, contacts; ...
        floats = np.frombuffer(buffer.float_buf(), np.float64).tolist()  # nx, ny; ...
        normals: dict[int, list[tuple[float, float]]] = {}
        for k in range(0, len(ints), 3):
            if ints[k + 2]:
                nx, ny = floats[2 * k // 3], floats[2 * k // 3 + 1]
                normals.setdefault(ints[k], []).append((nx, ny))
                normals.setdefault(ints[k + 1], []).append((-nx, -ny))
        return normals


def bumper_side(normals: list[tuple[float, float]] | None, heading: float) -> BumperSide | None:
    """Which side of the ring touches something, given the body's contact ``normals`` (see
    :class:`Contacts`) and its ``heading`` (its angle, unwrapped): ``front`` (±45°), ``left``,
    ``right``, ``back``. With several contacts, the one nearest the heading wins.

    The robot is a disc, so each contact lies along the contact normal from its centre: the
    normal alone gives the bearing (far cheaper than reading the contact points).
    """
    if not normals:
        return None
    bearing = min((wrap(math.atan2(ny, nx) - heading) for nx, ny in normals), key=abs)
    if abs(bearing) <= math.pi / 4:
        return "front"
    if abs(bearing) >= 3 * math.pi / 4:
        return "back"
    return "left" if bearing > 0 else "right"


def camera_sightings(
    space: pymunk.Space,
    pose: tuple[float, float, float],
    group: int,
    max_range: float,
    fov: float,
    occlusion: bool,
    entities: dict[pymunk.Shape, Entity],
) -> list[list[Any]]:
    """``[kind, id, status, range, bearing]`` for each entity whose centre is within range and
    the field of view (and, with ``occlusion``, not behind a wall), nearest first."""
    x, y, heading = pose
    near = pymunk.ShapeFilter(
        group=group, categories=CAT_QUERY, mask=CAT_ROBOT | CAT_BOX | CAT_IMMOVABLE | CAT_MARKER
    )
    walls = pymunk.ShapeFilter(group=group, categories=CAT_QUERY, mask=CAT_WALL)
    seen = []
    done: set[str] = set()
    for info in space.point_query((x, y), max_range, near):
        entity = entities.get(info.shape)
        if entity is None or entity.id in done:
            continue
        done.add(entity.id)
        cx, cy = entity.center()
        rng = math.hypot(cx - x, cy - y)
        bearing = wrap(math.atan2(cy - y, cx - x) - heading)
        if rng > max_range or abs(bearing) > fov / 2:
            continue
        if occlusion and space.segment_query_first((x, y), (cx, cy), 0.0, walls) is not None:
            continue
        seen.append([entity.kind, entity.id, entity.status(), rng, bearing])
    seen.sort(key=lambda s: (s[3], s[1]))
    return seen


def odometry_step(
    odom: list[float],
    before: tuple[float, float, float],
    after: tuple[float, float, float],
    trans_noise: float,
    rot_noise: float,
    drift: float,
    rng: np.random.Generator,
) -> None:
    """Advance the dead-reckoned pose ``odom`` in place by the wheel motion between two true
    poses (forward distance and turn, midpoint rule), with motion-proportional noise."""
    dx, dy = after[0] - before[0], after[1] - before[1]
    dth = wrap(after[2] - before[2])
    mid = before[2] + dth / 2
    d = dx * math.cos(mid) + dy * math.sin(mid)
    if trans_noise > 0.0:
        d += float(rng.normal(0.0, trans_noise * abs(d) + 1e-12))
    if rot_noise > 0.0 or drift > 0.0:
        dth += float(rng.normal(0.0, rot_noise * abs(dth) + drift * abs(d) + 1e-12))
    odom[2] = odom[2] + dth / 2
    odom[0] += d * math.cos(odom[2])
    odom[1] += d * math.sin(odom[2])
    odom[2] = wrap(odom[2] + dth / 2)


class Floor:
    """A grid of cells over the arena, each holding an integer and a colour name."""

    def __init__(self, width: float, height: float, cell: float) -> None:
        self.cell = cell
        self.shape = (max(1, math.ceil(width / cell)), max(1, math.ceil(height / cell)))
        self.values = np.zeros(self.shape, dtype=np.int64)
        self.colours: dict[tuple[int, int], str] = {}

    def index(self, x: float, y: float) -> tuple[int, int]:
        """The (column, row) of the cell holding point (x, y), clamped into the grid."""
        i = min(max(math.floor(x / self.cell), 0), self.shape[0] - 1)
        j = min(max(math.floor(y / self.cell), 0), self.shape[1] - 1)
        return i, j

    def read(self, x: float, y: float) -> tuple[int, str]:
        """Value and colour of the cell under (x, y)."""
        ij = self.index(x, y)
        return int(self.values[ij]), self.colours.get(ij, "")

    def read_all(self, xs: np.ndarray, ys: np.ndarray) -> list[list[Any]]:
        """``[value, colour]`` of the cell under each point: what :meth:`read` gives each, in
        a few numpy passes."""
        i = np.clip(np.floor(xs / self.cell), 0, self.shape[0] - 1).astype(np.intp)
        j = np.clip(np.floor(ys / self.cell), 0, self.shape[1] - 1).astype(np.intp)
        values = self.values[i, j].tolist()
        if not self.colours:
            return [[v, ""] for v in values]
        get = self.colours.get
        cells = zip(i.tolist(), j.tolist(), strict=True)
        return [[v, get(ij, "")] for v, ij in zip(values, cells, strict=True)]

    def write(self, x: float, y: float, value: int, colour: str) -> None:
        """Set the cell under (x, y)."""
        self.set(*self.index(x, y), value, colour)

    def set(self, i: int, j: int, value: int, colour: str) -> None:
        """Set cell (i, j)."""
        self.values[i, j] = value
        if colour:
            self.colours[(i, j)] = colour
        else:
            self.colours.pop((i, j), None)
