"""Pymunk bodies for the world's things: walls, obstacles, boxes, markers and robots.

Robots follow the tank pattern of pymunk's examples (docs/physics.md): a dynamic disc pulled by
a kinematic control body through a PivotJoint and a GearJoint with ``max_bias = 0``; the joints'
``max_force`` is the drive force, so a robot pushes with a bounded force whatever the time step.
Boxes get floor friction from a 3×3 grid of pivot joints to the static body, which couples
sliding and turning as a real box on a floor does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import pymunk

from ._spec import BoxSpec, ImmovableSpec, MarkerSpec, ObstacleSpec, RobotSpec

GRAVITY = 9.81
CAT_WALL = 0b00001
CAT_IMMOVABLE = 0b00010
CAT_BOX = 0b00100
CAT_ROBOT = 0b01000
CAT_MARKER = 0b10000
CAT_QUERY = 0b100000
SOLID = CAT_WALL | CAT_IMMOVABLE | CAT_BOX | CAT_ROBOT
GRID_FRICTION_SCALE = 1.04
"""A 3×3 friction grid reads ~3.8 % low (docs/physics.md); each point is scaled up by this."""
WALL_RADIUS = 0.05
SURFACE_FRICTION = 0.5


def _solid(shape: pymunk.Shape, category: int) -> pymunk.Shape:
    shape.filter = pymunk.ShapeFilter(categories=category)
    shape.friction = SURFACE_FRICTION
    return shape


def add_walls(space: pymunk.Space, width: float, height: float) -> list[pymunk.Shape]:
    """Four walls whose inner faces are the lines x=0, x=width, y=0, y=height."""
    r = WALL_RADIUS
    lo, hx, hy = -r, width + r, height + r
    corners = [(lo, lo), (hx, lo), (hx, hy), (lo, hy)]
    shapes = [
        _solid(pymunk.Segment(space.static_body, corners[i], corners[(i + 1) % 4], r), CAT_WALL)
        for i in range(4)
    ]
    space.add(*shapes)
    return shapes


def _poly_box(
    body: pymunk.Body,
    size: tuple[float, float],
    angle: float,
    center: tuple[float, float] = (0.0, 0.0),
) -> pymunk.Poly:
    w, h = size
    rot = pymunk.Transform.rotation(angle)
    move = pymunk.Transform.translation(*center)
    pts = [(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)]
    return pymunk.Poly(body, pts, transform=move @ rot, radius=0.0)


def add_obstacle(space: pymunk.Space, spec: ObstacleSpec, category: int = CAT_WALL) -> pymunk.Shape:
    """A static shape for an obstacle spec."""
    body = space.static_body
    shape: pymunk.Shape
    if spec.shape == "box":
        shape = _poly_box(body, spec.size, spec.angle, spec.center)
    elif spec.shape == "circle":
        shape = pymunk.Circle(body, spec.radius, spec.center)
    else:
        shape = pymunk.Segment(body, spec.a, spec.b, spec.radius)
    _solid(shape, category)
    space.add(shape)
    return shape


def add_immovable(space: pymunk.Space, spec: ImmovableSpec) -> pymunk.Shape:
    """A static object with an identity (the camera reports it)."""
    obstacle = ObstacleSpec(
        shape=spec.shape, center=spec.center, size=spec.size, angle=spec.angle, radius=spec.radius
    )
    return add_obstacle(space, obstacle, CAT_IMMOVABLE)


def add_marker(space: pymunk.Space, spec: MarkerSpec) -> pymunk.Shape:
    """A disc nothing collides with; only queries (camera) find it."""
    shape = pymunk.Circle(space.static_body, spec.radius, spec.center)
    shape.sensor = True
    shape.filter = pymunk.ShapeFilter(categories=CAT_MARKER, mask=CAT_QUERY)
    space.add(shape)
    return shape


@dataclass(slots=True)
class BoxBody:
    """A movable box and the joints that give it floor friction."""

    body: pymunk.Body
    shape: pymunk.Shape
    joints: list[pymunk.Constraint]


def add_box(space: pymunk.Space, spec: BoxSpec) -> BoxBody:
    """A dynamic box with its friction spread over a 3×3 grid of pivot points."""
    w, h = spec.size
    body = pymunk.Body(spec.mass, pymunk.moment_for_box(spec.mass, (w, h)))
    body.position = spec.center
    body.angle = spec.angle
    shape = _solid(_poly_box(body, spec.size, 0.0), CAT_BOX)
    per_point = spec.friction * spec.mass * GRAVITY / 9.0 * GRID_FRICTION_SCALE
    joints: list[pymunk.Constraint] = []
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            joint = pymunk.PivotJoint(space.static_body, body, (0, 0), (i * w / 3, j * h / 3))
            joint.max_bias = 0.0
            joint.max_force = per_point
            joints.append(joint)
    space.add(body, shape, *joints)
    return BoxBody(body, shape, joints)


@dataclass(slots=True)
class RobotBody:
    """A robot's disc, its kinematic control body and the two joints that bound its force."""

    body: pymunk.Body
    control: pymunk.Body
    shape: pymunk.Shape
    pivot: pymunk.PivotJoint
    gear: pymunk.GearJoint
    spec: RobotSpec

    def limit_force(self, force: float) -> None:
        """Bound the drive to ``force`` N (and the matching torque)."""
        self.pivot.max_force = force
        self.gear.max_force = force * self.spec.track / 2.0

    def parts(self) -> tuple[Any, ...]:
        """Everything to add to or remove from the space."""
        return (self.body, self.control, self.shape, self.pivot, self.gear)


def make_robot(spec: RobotSpec, pose: tuple[float, float, float], group: int) -> RobotBody:
    """Build (not add) a robot at ``pose``; its shape ignores queries made with ``group``."""
    body = pymunk.Body(spec.mass, pymunk.moment_for_circle(spec.mass, 0, spec.radius))
    body.position = pose[:2]
    body.angle = pose[2]
    shape = pymunk.Circle(body, spec.radius)
    shape.friction = SURFACE_FRICTION
    shape.filter = pymunk.ShapeFilter(group=group, categories=CAT_ROBOT)
    control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    control.position = pose[:2]
    control.angle = pose[2]
    pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
    pivot.max_bias = 0.0
    gear = pymunk.GearJoint(control, body, 0.0, 1.0)
    gear.max_bias = 0.0
    robot = RobotBody(body, control, shape, pivot, gear, spec)
    robot.limit_force(spec.force)
    return robot


def heading_vector(angle: float) -> tuple[float, float]:
    """Unit vector along ``angle``."""
    return (math.cos(angle), math.sin(angle))
