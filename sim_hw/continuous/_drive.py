"""The robots' drive each physics step: every control body set moving along its robot's heading.

A robot is a disc pulled by a kinematic control body (``_bodies.make_robot``); before each of a
tick's physics steps the control body gets the commanded speed ``v`` along the disc's heading
and the turn rate ``w``. :class:`RobotDrive` does it a robot at a time (three chipmunk calls
each, ~0.65 µs a robot a step); :class:`Driver` for the whole space in two calls and a few
numpy passes (``pymunk.batch``) from BATCH_FROM robots on. Both set the same numbers: the
headings are chipmunk's, their cosines and sines ``math``'s (``_sonar.cos_sin``), and every
other body's velocity is written back as it was read.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pymunk
import pymunk.batch
from pymunk._chipmunk import lib as _lib

from ._sonar import cos_sin

BATCH_FROM = 64
"""Robots from which the drive is batched."""

Drive = tuple[pymunk.Body, pymunk.Body, float, float]
"""One robot's drive: its disc, its control body, speed (m/s) and turn rate (rad/s)."""

_Fields = pymunk.batch.BodyFields


class RobotDrive:
    """The drive of a tick, a robot at a time."""

    def __init__(self, drives: Sequence[Drive]) -> None:
        self.drives = [(b._body, c._body, v, w) for b, c, v, w in drives]

    def __call__(self) -> None:
        # chipmunk's setters directly: the property setters cost ~2 µs a robot a step
        get_angle, set_vel, set_ang = (
            _lib.cpBodyGetAngle,
            _lib.cpBodySetVelocity,
            _lib.cpBodySetAngularVelocity,
        )
        cos, sin = math.cos, math.sin
        for body, control, v, w in self.drives:
            a = get_angle(body)
            set_vel(control, (v * cos(a), v * sin(a)))
            set_ang(control, w)


class Driver:
    """A world's drive: what sets every control body moving before each of a tick's steps."""

    def __init__(self, space: pymunk.Space) -> None:
        self.space = space
        self._ids = np.empty(0, np.uintp)  # the space's bodies in chipmunk's order, last tick
        self._bodies = self._controls = np.empty(0, np.intp)  # their rows: discs, controls
        self._v = self._w = np.empty(0)
        self._buffer = pymunk.batch.Buffer()
        self._write = pymunk.batch.Buffer()

    def tick(self, drives: Sequence[Drive]) -> Callable[[], None]:
        """The drive of a tick of ``drives`` (the space's bodies must not change until its
        steps are done): a robot at a time below BATCH_FROM robots, else batched."""
        if len(drives) < BATCH_FROM:
            return RobotDrive(drives)
        self._rows(drives)
        self._v = np.array([d[2] for d in drives], float)
        self._w = np.array([d[3] for d in drives], float)
        return self._step

    def _rows(self, drives: Sequence[Drive]) -> None:
        """Each drive's disc and control body's row in chipmunk's order of the space's bodies
        (kept while the space holds the same bodies in the same order)."""
        buffer = self._buffer
        buffer.clear()
        pymunk.batch.get_space_bodies(self.space, _Fields.BODY_ID, buffer)
        ids = np.frombuffer(buffer.int_buf(), np.uintp).copy()
        if len(self._bodies) == len(drives) and np.array_equal(ids, self._ids):
            return
        row = {i: k for k, i in enumerate(ids.tolist())}
        self._bodies = np.array([row[d[0].id] for d in drives], np.intp)
        self._controls = np.array([row[d[1].id] for d in drives], np.intp)
        self._ids = ids

    def _step(self) -> None:
        """Set every control body moving along its disc's heading (before a physics step)."""
        buffer = self._buffer
        buffer.clear()
        fields = _Fields.ANGLE | _Fields.VELOCITY | _Fields.ANGULAR_VELOCITY
        pymunk.batch.get_space_bodies(self.space, fields, buffer)
        now = np.frombuffer(buffer.float_buf(), np.float64).reshape(-1, 4)  # a, vx, vy, w
        c, s = cos_sin(now[self._bodies, 0])
        out = now[:, 1:].copy()  # every other body as it was
        out[self._controls, 0] = self._v * c
        out[self._controls, 1] = self._v * s
        out[self._controls, 2] = self._w
        self._write.set_float_buf(out.reshape(-1))
        pymunk.batch.set_space_bodies(
            self.space, _Fields.VELOCITY | _Fields.ANGULAR_VELOCITY, self._write
        )
