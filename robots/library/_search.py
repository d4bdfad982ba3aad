"""MOVER's search and recognition (Jennings et al., section 4.1 "Search" and "Recognition").

Search is a random walk: wander in a randomly chosen direction until bumping into something,
then test it with a predicate; go on until something passes. Recognition is physical: an
object is the one to rescue if the robot can move it with a fixed, medium push force, so walls
and immovable objects are ignored. The decision rules (:class:`Wander`, :func:`moved`,
:func:`teammate_ahead`, :func:`locate`) are plain code over readings; :func:`search` and
:func:`movable` wire them to the hardware.
"""

from __future__ import annotations

import math
import random
from collections.abc import Awaitable, Callable, Sequence
from typing import Any, NamedTuple, Protocol

from robots._robot import Robot
from robots.hal import BumperSide, Sighting

from ._geometry import Point, Pose, Rect, Region, ahead, bearing_to, clip, distance, wrap
from ._goto import approach, turn_to


class Rng(Protocol):
    """What the library needs of a random generator (``random.Random`` or numpy's)."""

    def uniform(self, low: float, high: float) -> Any:
        """A float drawn uniformly from [low, high)."""
        ...


class Found(NamedTuple):
    """What a successful search returns (the results of the OR step, section 4.2 item 4).

    A NamedTuple so that it crosses the wire as a plain list; :meth:`load` rebuilds it.
    ``location`` is the object's estimated centre and ``pose`` the finder's pose, both in the
    finder's odometry frame.
    """

    object_id: str | None
    location: Point
    pose: Pose

    @classmethod
    def load(cls, data: Sequence[Any]) -> Found:
        """A Found from itself or from its wire form (a list of lists)."""
        oid, loc, pose = data
        return cls(
            oid, (float(loc[0]), float(loc[1])), (float(pose[0]), float(pose[1]), float(pose[2]))
        )


# -- decision rules --------------------------------------------------------------------------


class Wander:
    """The random walk of section 4.1: pick a random heading, drive until something is hit.

    ``step(pose, bump, front)`` → ``("drive", v, w)`` or ``("check", 0, 0)`` when the front of
    the bumper touches something (the caller then tests it and calls :meth:`rejected` if it
    is not wanted). A side or rear contact, or a rejected object, makes the robot back off and
    turn to a random heading away from it. Sonar only slows the approach, so contact is gentle.

    With a ``region`` (a :data:`Region`, a predicate on positions), a walk that finds itself
    outside turns back toward the centre of a :class:`Rect`, or else the mean of the positions
    it has held inside the region, within ``reenter`` rad of it, and wanders on from there.
    """

    def __init__(
        self,
        rng: Rng,
        *,
        speed: float = 0.4,
        creep: float = 0.12,
        slow_range: float = 0.3,
        gain: float = 2.5,
        max_turn: float = 1.5,
        backoff: float = 0.25,
        region: Region | None = None,
        reenter: float = 0.5,
    ) -> None:
        self.rng = rng
        self.region, self.reenter = region, reenter
        self._inside: Point | None = None  # the mean of the positions held inside
        self._inside_n = 0
        self.speed, self.creep, self.slow_range = speed, creep, slow_range
        self.gain, self.max_turn, self.backoff = gain, max_turn, backoff
        self.mode = "start"
        self.goal = 0.0
        self._back_from: Point = (0.0, 0.0)
        self._away = 0.0
        self._back_steps = 0

    def _turn_away(self, obstacle_direction: float) -> None:
        # a random heading in the half-plane away from the obstacle
        self.goal = wrap(obstacle_direction + math.pi + float(self.rng.uniform(-1.2, 1.2)))
        self.mode = "turn"

    def rejected(self, pose: Pose, direction: float | None = None) -> None:
        """The thing ahead is not wanted: back off, then wander away from it."""
        self.mode = "back"
        self._back_steps = 0
        self._back_from = (pose[0], pose[1])
        self._away = pose[2] if direction is None else direction

    def _keep_in(self, pose: Pose) -> None:
        # outside the region and heading away from it: aim back (not while backing off a
        # contact, so that it still leaves what it touched)
        assert self.region is not None
        if self.region(pose[:2]):
            n = self._inside_n = self._inside_n + 1
            x, y = self._inside or (0.0, 0.0)
            self._inside = (x + (pose[0] - x) / n, y + (pose[1] - y) / n)
            return
        back = self.region.centre if isinstance(self.region, Rect) else self._inside
        if back is None or self.mode == "back":
            return
        towards = wrap(bearing_to(pose, back) + pose[2])
        if abs(wrap(self.goal - towards)) > self.reenter:
            self.goal = wrap(towards + float(self.rng.uniform(-self.reenter, self.reenter)))
            self.mode = "turn"

    def step(self, pose: Pose, bump: BumperSide | None, front: float) -> tuple[str, float, float]:
        """The next command from the dead-reckoned pose, the bumper and the front sonar range."""
        heading = pose[2]
        if self.mode == "start":
            self.goal = float(self.rng.uniform(-math.pi, math.pi))
            self.mode = "turn"
        if self.region is not None:
            self._keep_in(pose)
        if self.mode == "back":
            self._back_steps += 1
            far = distance(pose, self._back_from) >= self.backoff
            if not far and bump != "back" and self._back_steps < 30:
                return ("drive", -self.creep * 1.5, 0.0)
            self._turn_away(self._away)
        elif bump == "front":
            return ("check", 0.0, 0.0)
        elif bump in ("left", "right"):
            side = heading + (math.pi / 2 if bump == "left" else -math.pi / 2)
            self._turn_away(side)
        err = wrap(self.goal - heading)
        turn = clip(self.gain * err, -self.max_turn, self.max_turn)
        if self.mode == "turn":
            if abs(err) > 0.1:
                return ("drive", 0.0, turn)
            self.mode = "drive"
        v = self.speed if front > self.slow_range else self.creep
        return ("drive", v, turn)


def moved(displacement: float, threshold: float = 0.005) -> bool:
    """Recognition (section 4.1): did the pushed object move by more than ``threshold`` m?

    Walls and immovable objects read exactly 0; the demo world's 2-robot box does not slide
    under one robot but pivots by centimetres when pushed off-centre (docs/physics.md).
    """
    return displacement > threshold


def teammate_ahead(sightings: Sequence[Sighting], reach: float = 0.45, cone: float = 0.6) -> bool:
    """Whether the thing just bumped is another robot (seen straight ahead and close).

    A teammate would "move" when pushed because it drives itself: it must not pass the test.
    """
    return any(s.kind == "robot" and s.range < reach and abs(s.bearing) < cone for s in sightings)


def kind_ahead(sightings: Sequence[Sighting], reach: float = 0.9, cone: float = 0.8) -> str | None:
    """The camera's kind of the nearest thing straight ahead within ``reach`` (the thing just
    bumped), or None."""
    for s in sightings:
        if s.range < reach and abs(s.bearing) < cone:
            return s.kind
    return None


def locate(
    pose: Pose, sightings: Sequence[Sighting], radius: float, reach: float = 0.9, cone: float = 0.8
) -> tuple[str | None, Point]:
    """Where the object just bumped is: (id, centre) from the camera's nearest sighting ahead
    that is not a robot, else a point half a box beyond the contact point."""
    for s in sightings:
        if s.kind != "robot" and s.range < reach and abs(s.bearing) < cone:
            return s.id, ahead(pose, s.range, s.bearing)
    return None, ahead(pose, radius + 0.3)


# -- procedures ------------------------------------------------------------------------------

Predicate = Callable[[Robot], Awaitable[bool]]


def _front(robot: Robot) -> float:
    sonar = robot.hw.sonar
    if sonar is None:
        return math.inf
    ranges = sonar.ranges()
    near = [r for r, a in zip(ranges, sonar.angles, strict=False) if abs(wrap(a)) < 0.6]
    return min(near, default=sonar.max_range)


def _sightings(robot: Robot) -> tuple[Sighting, ...]:
    return robot.hw.camera.sightings() if robot.hw.camera is not None else ()


async def search(
    robot: Robot,
    predicate: Predicate,
    terminator: Callable[[], bool] | None = None,
    rng: Rng | None = None,
    *,
    wander: Wander | None = None,
    radius: float = 0.15,
    region: Region | None = None,
) -> Found | None:
    """Random-walk until an object passing ``predicate`` is found (section 4.3, ``search``).

    ``terminator`` is polled every tick; when it returns True the search gives up and returns
    None. ``region`` (a :data:`Region`: a :class:`Rect` or any predicate on positions) limits
    the search: the walk keeps inside it, and a thing bumped whose estimated centre lies
    outside is left untested (a ``wander`` of one's own keeps to its own ``region``). The
    motors are stopped on the way out, also when the search is cancelled (a lost
    ``distributed_or``).
    """
    hw = robot.hw
    walk = wander or Wander(rng if rng is not None else random.Random(robot.id), region=region)
    bumper = hw.bumper
    try:
        while terminator is None or not terminator():
            pose = hw.odometry.pose()
            bump = bumper.side() if bumper is not None else None
            action, v, w = walk.step(pose, bump, _front(robot))
            if action == "check":
                hw.drive.stop()
                await hw.clock.tick()
                here = hw.odometry.pose()
                oid, where = locate(here, _sightings(robot), radius)
                if (region is None or region(where)) and await predicate(robot):
                    robot.log.info("found %s at %.2f, %.2f", oid, *where)
                    return Found(oid, where, here)
                walk.rejected(hw.odometry.pose(), here[2])
                continue
            hw.drive.set_velocity(v, w)
            await hw.clock.tick()
        return None
    finally:
        hw.drive.stop()


async def movable(
    robot: Robot,
    force: float = 50.0,
    duration: float = 1.0,
    threshold: float = 0.005,
    probe: float = 0.5,
) -> bool:
    """MOVER's recognition (section 4.1): can this robot move what is in front of it?

    Push with a medium force (50 N of the demo robots' 70 N); if the object does not give,
    back off a little, turn by ``probe`` rad one way then the other and push again
    (off-centre, and in case the contact was not straight ahead). Walls and immovable
    objects never move (they read exactly 0 m); a box one robot can slide moves by
    centimetres; the demo's 2-robot box reads ~1e-8 m under a square push and pivots only
    under a near-corner push of more than ~52 N (docs/physics.md), so at 50 N it is not
    "movable" by one robot — use :func:`sees` for it. Teammates (seen by the camera) are never
    movable. The motors are stopped on the way out.
    """
    hw = robot.hw
    if hw.push is None or teammate_ahead(_sightings(robot)):
        return False
    try:
        start = hw.odometry.pose()
        for turn in (0.0, probe, -probe):
            if turn:  # back off 6 cm, turn, creep back into contact off-centre
                hw.drive.set_velocity(-0.1, 0.0)
                await hw.clock.sleep(0.6)
                await turn_to(robot, wrap(start[2] + turn))
                if not await approach(robot, wrap(start[2] + turn), limit=0.45):
                    continue
            got = await hw.push.push(force, duration)
            if moved(got.displacement, threshold):
                return True
        return False
    finally:
        hw.drive.stop()


def sees(kind: str = "box") -> Predicate:
    """A recognition predicate by camera: the object just bumped is seen as ``kind``.

    Section 4.1 names vision-based recognition as the upgrade of the push test. The demo's
    2-robot box needs it: one robot's medium push does not move that box at all (it reads
    ~1e-8 m, as a wall does), which is physically right — one robot cannot move it.
    """

    async def predicate(robot: Robot) -> bool:
        return kind_ahead(_sightings(robot)) == kind

    predicate.__name__ = f"sees_{kind}"
    return predicate


def recognition(name: str) -> Predicate:
    """A recognition predicate by name: ``"push"`` (:func:`movable`, the paper's test) or a
    camera kind such as ``"box"`` (:func:`sees`)."""
    return movable if name == "push" else sees(name)
