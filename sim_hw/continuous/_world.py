"""The continuous world: one pymunk space, its things, its robots, and the simulated clock.

The world is synchronous and knows nothing of asyncio or zenoh. A control tick is
``STEPS_PER_TICK`` physics steps of ``DT``: robots' commands are applied at the start of the tick
(drive velocities are re-aimed along the heading every physics step), and their readings are
measured at the end. Same seed, same world, same commands → the same trajectories, bit for bit.
"""

from __future__ import annotations

import logging
import math
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
import pymunk
from pymunk._chipmunk import lib as _lib

from robots.hal import MARK, MARKED

from . import _bodies, _devices, _drive
from ._contract import DT, STEPS_PER_TICK, TICK, Command, Readings
from ._sonar import Discs, Sonar, sonar_batch
from ._spec import RobotSpec, WorldSpec

_T = TypeVar("_T")

log = logging.getLogger("sim_hw.world")

BATCH_FROM = 128
"""Robots from which a tick's sonar is read in one batch (``_sonar``; measured: docs/physics.md)."""
PUSH_REACH = 0.1
"""How far ahead of its rim a robot looks for the object it is asked to push (m)."""


@dataclass(slots=True)
class _Push:
    object_id: str | None
    body: pymunk.Body | None
    start: tuple[float, float]


@dataclass(slots=True)
class _Robot:
    id: str
    group: int
    parts: _bodies.RobotBody
    rng: np.random.Generator
    odom: list[float]
    last: tuple[float, float, float]
    v: float = 0.0
    w: float = 0.0
    led: str = ""
    push_force: float | None = None
    push: _Push | None = None
    readings: Readings = field(init=False)
    angles: tuple[float, ...] = ()
    sonar: Sonar | None = None
    body_id: int = field(init=False)  # its disc's id (pymunk's property costs ~1 µs a read)


def _pose(body: pymunk.Body) -> tuple[float, float, float]:
    p = _lib.cpBodyGetPosition(body._body)
    return (p.x, p.y, _devices.wrap(_lib.cpBodyGetAngle(body._body)))


class World:
    """A pymunk world built from a :class:`WorldSpec`; robots join and leave at run time.

    ``seed`` seeds every robot's sensor noise (through a generator per robot derived from the
    seed and the robot's id) and nothing else: the physics has no randomness.
    """

    def __init__(self, spec: WorldSpec, seed: int = 0) -> None:
        self.spec = spec
        self.seed = seed
        self.tick = 0
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.iterations = 10
        space.collision_slop = 0.003
        self.space = space
        self.entities: dict[pymunk.Shape, _devices.Entity] = {}
        self.boxes: dict[str, _bodies.BoxBody] = {}
        self.robots: dict[str, _Robot] = {}
        self._next_group = 1
        self._spawn_index = 0
        _bodies.add_walls(space, *spec.size)
        for ob in spec.obstacles:
            _bodies.add_obstacle(space, ob)
        for box in spec.boxes:
            made = _bodies.add_box(space, box)
            self.boxes[box.id] = made
            self.entities[made.shape] = _devices.Entity(
                "box", box.id, _center_of(made.body), _const(box.status), made.body
            )
        for im in spec.immovables:
            shape = _bodies.add_immovable(space, im)
            self.entities[shape] = _devices.Entity(
                "immovable", im.id, _const(im.center), _const(im.status)
            )
        self.marked: dict[str, float] = {}
        """Markable markers marked so far (``MarkerSpec.hears``) and the time each was marked."""
        self._markable = {mk.id: mk for mk in spec.markers if mk.hears > 0.0}
        for mk in spec.markers:
            shape = _bodies.add_marker(space, mk)
            status = _marker_status(self.marked, mk.id, mk.status)
            self.entities[shape] = _devices.Entity(mk.kind, mk.id, _const(mk.center), status)
        self.floor = _devices.Floor(spec.size[0], spec.size[1], spec.cell)
        for i, j, value, colour in spec.floor:
            self.floor.set(i, j, value, colour)
        self._contacts = _devices.Contacts()  # every body's contacts, read once a tick
        self._driver = _drive.Driver(space)
        # what a sonar ray may hit besides robots (asked of chipmunk: see _sonar)
        self._others = [
            sh
            for sh in space.shapes
            if sh.filter.categories & _bodies.SOLID & ~_bodies.CAT_ROBOT and not sh.sensor
        ]

    @property
    def time(self) -> float:
        """Simulated seconds since the start."""
        return self.tick * TICK

    # -- robots ------------------------------------------------------------------------------

    def add_robot(self, robot_id: str, spec: RobotSpec | None = None) -> Readings:
        """Spawn a robot and return its first readings.

        Without ``spec`` the world file's entry for ``robot_id`` is used, else the defaults.
        Without a pose, the robot takes the next free spawn point along the bottom-left.
        """
        if robot_id in self.robots:
            raise ValueError(f"robot {robot_id!r} is already in the world")
        spec = spec or self.spec.robots.get(robot_id) or self.spec.robot
        pose = spec.pose or self._spawn_point(spec.radius)
        group = self._next_group
        self._next_group += 1
        parts = _bodies.make_robot(spec, pose, group)
        self.space.add(*parts.parts())
        rng = np.random.default_rng([self.seed, zlib.crc32(robot_id.encode())])
        start = (float(pose[0]), float(pose[1]), float(pose[2]))
        robot = _Robot(robot_id, group, parts, rng, list(pose), start, led=spec.led)
        robot.body_id = parts.body.id
        robot.angles = spec.sonar.angles() if spec.sonar else ()
        if spec.sonar:
            sonar = spec.sonar
            robot.sonar = Sonar(0, group, robot.angles, sonar.max_range, sonar.noise, rng)
        self.robots[robot_id] = robot
        self.entities[parts.shape] = _devices.Entity(
            "robot", robot_id, _center_of(parts.body), lambda: robot.led, parts.body
        )
        robot.readings = self._measure(robot)
        return robot.readings

    def remove_robot(self, robot_id: str) -> None:
        """Take a robot out of the world (no error if it is not there)."""
        robot = self.robots.pop(robot_id, None)
        if robot is None:
            return
        self.entities.pop(robot.parts.shape, None)
        self.space.remove(*robot.parts.parts())

    def respawn_robots(self) -> None:
        """Re-create every robot, in id order, from its spec (only before the first tick)."""
        if self.tick:
            raise RuntimeError("robots can be respawned only before the first tick")
        specs = {rid: r.parts.spec for rid, r in self.robots.items()}
        for rid in specs:
            self.remove_robot(rid)
        self._spawn_index = 0
        for rid in sorted(specs):
            self.add_robot(rid, specs[rid])

    def _spawn_point(self, radius: float) -> tuple[float, float, float]:
        w, _h = self.spec.size
        gap = 4 * radius
        per_row = max(1, int((w - gap) // gap))
        k = self._spawn_index
        self._spawn_index += 1
        return (gap * (1 + k % per_row), gap * (1 + k // per_row), 0.0)

    def set_command(self, robot_id: str, command: Command | Mapping[str, Any]) -> None:
        """Store a robot's command; it applies from the next tick on."""
        robot = self.robots[robot_id]
        spec = robot.parts.spec
        if "v" in command:
            robot.v = min(max(float(command["v"]), -spec.max_speed), spec.max_speed)
        if "w" in command:
            robot.w = min(max(float(command["w"]), -spec.max_turn), spec.max_turn)
        if command.get("led") is not None:
            robot.led = str(command["led"])
        if "push" in command:
            self._set_push(robot, command["push"])
        floor = command.get("floor")
        if floor is not None:
            x, y = robot.parts.body.position
            self.floor.write(x, y, int(floor[0]), str(floor[1]))

    def _set_push(self, robot: _Robot, force: float | None) -> None:
        parts = robot.parts
        if force is None:
            if robot.push_force is not None:
                parts.limit_force(parts.spec.force)
            robot.push_force, robot.push = None, None
            return
        force = min(float(force), parts.spec.force)
        parts.limit_force(force)
        if robot.push is None:
            robot.push = self._find_pushed(robot)
        robot.push_force = force

    def _find_pushed(self, robot: _Robot) -> _Push:
        body = robot.parts.body
        x, y, th = _pose(body)
        r = robot.parts.spec.radius
        c, s = math.cos(th), math.sin(th)
        query = pymunk.ShapeFilter(
            group=robot.group, categories=_bodies.CAT_QUERY, mask=_bodies.SOLID
        )
        hit = self.space.segment_query_first(
            (x, y), (x + c * (r + PUSH_REACH), y + s * (r + PUSH_REACH)), 0.0, query
        )
        if hit is None:
            return _Push(None, None, (0.0, 0.0))
        entity = self.entities.get(hit.shape)
        if entity is None:
            return _Push("wall", None, (0.0, 0.0))
        if entity.body is None:
            return _Push(entity.id, None, (0.0, 0.0))
        px, py = entity.body.position
        return _Push(entity.id, entity.body, (float(px), float(py)))

    # -- time --------------------------------------------------------------------------------

    def step(self) -> None:
        """Advance one control tick and measure every robot's readings."""
        robots = list(self.robots.values())
        drives = [(r.parts.body, r.parts.control, r.v, r.w) for r in robots]
        drive = self._driver.tick(drives)
        for _ in range(STEPS_PER_TICK):
            drive()
            self.space.step(DT)
        self.tick += 1
        if self._markable:
            self._hear_marks(robots)
        self._measure_all(robots)

    def _measure_all(self, robots: list[_Robot]) -> None:
        """Every robot's readings after a tick: the sonar of all of them in one batch once
        there are BATCH_FROM robots (below that, a query per ray is quicker; both read alike)."""
        normals = self._contacts.read(self.space)
        if len(robots) < BATCH_FROM:
            for robot in robots:
                robot.readings = self._measure(robot, normals)
            return
        poses = [_pose(r.parts.body) for r in robots]
        sonars: list[Sonar] = []
        for i, (robot, pose) in enumerate(zip(robots, poses, strict=True)):
            self._odometry(robot, pose)  # (its noise is drawn before the sonar's)
            if robot.sonar is not None:
                robot.sonar.index = i
                sonars.append(robot.sonar)
        discs = Discs(
            np.array([p[0] for p in poses]),
            np.array([p[1] for p in poses]),
            np.array([p[2] for p in poses]),
            np.array([r.parts.spec.radius for r in robots]),
            np.array([r.group for r in robots]),
        )
        ranges = iter(sonar_batch(self.space, discs, sonars, self._others))
        floors = self.floor.read_all(discs.x, discs.y)
        for robot, pose, floor in zip(robots, poses, floors, strict=True):
            ranged = next(ranges) if robot.sonar else None
            robot.readings = self._readings(robot, pose, ranged, normals, floor)

    def _hear_marks(self, robots: list[_Robot]) -> None:
        """Markable markers take the ``mark:<id>`` LED messages of robots within ``hears``."""
        for robot in robots:
            if not robot.led.startswith(MARK):
                continue
            mk = self._markable.get(robot.led[len(MARK) :])
            if mk is None or mk.id in self.marked:
                continue
            x, y = robot.parts.body.position
            if math.hypot(x - mk.center[0], y - mk.center[1]) <= mk.hears:
                self.marked[mk.id] = self.time

    def _odometry(self, robot: _Robot, pose: tuple[float, float, float]) -> None:
        od = robot.parts.spec.odometry
        _devices.odometry_step(
            robot.odom, robot.last, pose, od.trans_noise, od.rot_noise, od.drift, robot.rng
        )
        robot.last = pose

    def _measure(
        self, robot: _Robot, normals: dict[int, list[tuple[float, float]]] | None = None
    ) -> Readings:
        """One robot's readings now (a robot just placed), its sonar a query per ray;
        ``normals``: every body's contacts (see ``_devices.Contacts``), read now if not given."""
        if normals is None:
            normals = self._contacts.read(self.space)
        spec = robot.parts.spec
        pose = _pose(robot.parts.body)
        self._odometry(robot, pose)
        sonar = spec.sonar
        ranges = (
            _devices.sonar_ranges(
                self.space,
                pose,
                spec.radius,
                robot.group,
                robot.angles,
                sonar.max_range,
                sonar.noise,
                robot.rng,
            )
            if sonar
            else None
        )
        floor = list(self.floor.read(pose[0], pose[1]))
        return self._readings(robot, pose, ranges, normals, floor)

    def _readings(
        self,
        robot: _Robot,
        pose: tuple[float, float, float],
        ranges: list[float] | None,
        normals: dict[int, list[tuple[float, float]]],
        floor: list[Any],
    ) -> Readings:
        spec = robot.parts.spec
        contacts = normals.get(robot.body_id)
        cam = spec.camera
        sightings = (
            _devices.camera_sightings(
                self.space,
                pose,
                robot.group,
                cam.max_range,
                cam.fov,
                cam.occlusion,
                self.entities,
            )
            if cam
            else None
        )
        return {
            "tick": self.tick,
            "t": self.time,
            "sonar": ranges,
            "bump": (
                _devices.bumper_side(contacts, _lib.cpBodyGetAngle(robot.parts.body._body))
                if contacts
                else None
            ),
            "odom": list(robot.odom),
            "cam": sightings,
            "loc": list(pose) if spec.radio else None,
            "floor": floor,
            "push": self._push_reading(robot),
        }

    def _push_reading(self, robot: _Robot) -> list[Any] | None:
        push = robot.push
        if push is None:
            return None
        if push.body is None:
            return [push.object_id, 0.0]
        x, y = push.body.position
        return [push.object_id, math.hypot(x - push.start[0], y - push.start[1])]

    def readings(self, robot_id: str) -> Readings:
        """A robot's readings from the end of the last tick."""
        return self.robots[robot_id].readings

    # -- views -------------------------------------------------------------------------------

    def pose(self, robot_id: str) -> tuple[float, float, float]:
        """A robot's true pose."""
        return _pose(self.robots[robot_id].parts.body)

    def box_pose(self, box_id: str) -> tuple[float, float, float]:
        """A box's true pose."""
        return _pose(self.boxes[box_id].body)

    def snapshot(self) -> dict[str, Any]:
        """Poses of robots (with their LED) and boxes, for a state stream or a recording."""
        return {
            "tick": self.tick,
            "t": self.time,
            "robots": {
                rid: [*_pose(r.parts.body), r.led] for rid, r in sorted(self.robots.items())
            },
            "boxes": {bid: list(_pose(b.body)) for bid, b in sorted(self.boxes.items())},
            "marked": dict(self.marked),
        }


def _center_of(body: pymunk.Body) -> Callable[[], tuple[float, float]]:
    def center() -> tuple[float, float]:
        x, y = body.position
        return (float(x), float(y))

    return center


def _const(value: _T) -> Callable[[], _T]:
    return lambda: value


def _marker_status(marked: dict[str, float], marker: str, status: str) -> Callable[[], str]:
    return lambda: MARKED if marker in marked else status
