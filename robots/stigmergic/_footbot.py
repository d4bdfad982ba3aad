"""The foot-bot (Ducatelle et al., sections 4.3–4.4): follow eye-bots between source and target.

Under an eye-bot a foot-bot hears its instruction (:class:`Heard`: θ_s and θ_t, and θ0 as its
upward camera reads it), takes θ_n = θ0 + θ_s (or θ_t, for its goal), turns to it and drives
``d`` metres, or until it is under another eye-bot. If no eye-bot was reached by then it heads
for the closest eye-bot its omnidirectional camera sees, and if it sees none it moves at random
(a random turn, a random distance, again). Obstacles are avoided reactively.

The forward/backward rule (4.4): an instruction within ±π/2 of the direction received from the
previous eye-bot is *forward*: the foot-bot follows it and ignores that eye-bot from then on. A
*backward* one is followed too, but the foot-bot keeps listening to the same eye-bot, and takes
its next instruction (forward: then it stops listening; backward: it keeps going that way).

LEDs: the beacon always shows whether it is avoiding an obstacle; the front LED shows the goal,
and is off whenever the movement is not representative of the way from source to target:
avoiding an obstacle, following a backward instruction, or not following an instruction at all
(heading for an eye-bot in view, moving at random) — and, a choice made here, while it turns on
the spot to a new direction (its heading then sweeps through every direction, and an eye-bot
that reads θ_f off it would learn noise).

Choices the paper leaves open, taken here:

* the first instruction after a goal is reached (or ever) counts as forward: there is no
  previous direction to compare with. Reaching the goal turns the foot-bot's goal over;
* "the closest eye-bot in view" leaves out the eye-bot it last followed (it drove ``d`` away
  from it, so that it would not be sent back by it): eye-bots seen within
  ``same_eyebot`` metres of where it heard that one are taken for it;
* random movement turns by a uniform angle in [-π, π) and drives a uniform distance in
  [0.5, ``d``] metres;
* every leg (following, seeking, random) is given up after twice the time it should take
  (a wall in the way): a seek leg that reached no eye-bot is followed by a random one, so
  that an eye-bot seen behind a wall does not hold the foot-bot there;
* while avoiding, the distance driven counts towards ``d``. Avoiding is reactive: with an
  obstacle within ±π/2 of its heading (closer than the proximity threshold) the foot-bot turns
  away from it, the same way until it is clear (turning towards whichever side is freer at
  each step makes it rock in front of a wall for ever), and then drives ``escape`` metres
  straight on before it turns back to its way. An obstacle behind it is not avoided. One
  straight ahead (a head-on contact) is passed on a side drawn by a seeded coin, so that the
  rule is the same under mirroring; the old rule, always to the right (a bias that favours
  one of two mirrored ways), is ``Motion(head_on_right=True)``.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from robots.library._geometry import Point, Pose, distance, wrap

from ._eyebot import Goal


@dataclass(frozen=True)
class Heard:
    """An eye-bot's instruction as a foot-bot under it gets it: who sent it, θ0 as the upward
    camera reads it (radians in the foot-bot's frame), and θ_s, θ_t relative to θ0."""

    eyebot: str
    reference: float
    to_source: float
    to_target: float

    def direction(self, goal: Goal, pose: Pose) -> float:
        """θ_n for ``goal``, as a heading in the odometry frame of ``pose``."""
        relative = self.to_target if goal is Goal.TARGET else self.to_source
        return wrap(pose[2] + self.reference + relative)


@dataclass(frozen=True)
class FootPerception:
    """What a foot-bot senses in one time step.

    ``pose`` is its odometry; ``heard`` the instruction of the eye-bot above it (None when it
    is under none); ``eyebots`` the (distance, bearing) of the eye-bots its omnidirectional
    camera sees; ``obstacle`` the bearing of the nearest obstacle within its proximity range
    (None: clear); ``at_source`` / ``at_target`` whether it is in that area.
    """

    pose: Pose
    heard: Heard | None = None
    eyebots: Sequence[tuple[float, float]] = ()
    obstacle: float | None = None
    at_source: bool = False
    at_target: bool = False


@dataclass(frozen=True)
class FootCommand:
    """Wheel speeds as (v m/s, ω rad/s), the front LED (the goal's colour, or None: off) and
    whether the beacon shows obstacle avoidance."""

    v: float
    w: float
    front: Goal | None
    avoiding: bool


class Mode(enum.Enum):
    """What a foot-bot is doing."""

    FOLLOW = "follow"  # an eye-bot's instruction
    SEEK = "seek"  # heading for the closest eye-bot in view
    RANDOM = "random"  # random movement


@dataclass(frozen=True)
class Motion:
    """Speeds and distances (defaults: the paper's d = 2 m; speeds chosen for the world)."""

    d: float = 2.0
    speed: float = 0.3
    turn_rate: float = 1.5
    aligned: float = 0.15  # radians: drive only once the heading is this close
    same_eyebot: float = 1.0
    escape: float = 0.3  # metres driven straight on once an obstacle is no longer ahead
    dt: float = 0.1  # seconds between two steps
    head_on_right: bool = False  # the old rule: an obstacle straight ahead is always passed right


HEAD_ON = 1e-6
"""An obstacle at a bearing within this of 0 (radians) is straight ahead (the front ray)."""


class FootBot:
    """A foot-bot's navigation; its randomness from ``rng``. :meth:`step` once per time step."""

    def __init__(
        self, rng: np.random.Generator, goal: Goal = Goal.TARGET, motion: Motion | None = None
    ) -> None:
        self.rng = rng
        self.goal = goal
        self.motion = motion or Motion()
        self.mode = Mode.RANDOM
        self.heading: float | None = None  # the heading it drives (odometry frame)
        self.left = 0.0  # metres still to drive in this leg
        self.patience = 0  # steps this leg may still take (a leg blocked by a wall ends)
        self.may_seek = True  # False after a seek leg that reached no eye-bot: a random leg
        self.source: str | None = None  # the eye-bot it last took an instruction from
        self.received: float | None = None  # the direction it last received from it
        self.reference: float | None = None  # the direction received from the one before
        self.locked = False  # the source gave a forward instruction: not listened to any more
        self.last_heard_at: Point | None = None  # where it last took an instruction
        self.backward = False  # it follows a backward instruction
        self.trips = 0  # goals reached
        self._last: Point | None = None
        self._turning = 0.0  # the way it turns while an obstacle is ahead (kept until clear)
        self._escape = 0.0  # metres still to drive straight after an obstacle

    def step(self, seen: FootPerception) -> FootCommand:
        """Sense, decide, command."""
        pose = seen.pose
        if self._last is not None:
            moved = distance(self._last, pose[:2])
            self.left -= moved
            self._escape -= moved
        self._last = pose[:2]
        self.patience -= 1
        self._goal_reached(seen)
        if seen.heard is not None:
            self._hear(seen.heard, pose)
        if self.mode is Mode.FOLLOW and self._leg_over():
            self.mode, self.may_seek = Mode.SEEK, True
        if self.mode is not Mode.FOLLOW:
            self._wander(seen)
        if seen.obstacle is not None and abs(seen.obstacle) < math.pi / 2:
            return self._avoid(seen.obstacle)
        self._turning = 0.0
        if self._escape > 0.0:  # clear of it: away a little before turning back to the way
            return FootCommand(self.motion.speed, 0.0, None, False)
        return self._drive(pose)

    # -- decisions -------------------------------------------------------------------------------

    def _goal_reached(self, seen: FootPerception) -> None:
        reached = seen.at_target if self.goal is Goal.TARGET else seen.at_source
        if not reached:
            return
        self.trips += 1
        self.goal = self.goal.other
        self.source = self.received = self.reference = None
        self.mode, self.left, self.backward, self.locked = Mode.SEEK, 0.0, False, False

    def _hear(self, heard: Heard, pose: Pose) -> None:
        if heard.eyebot == self.source and self.locked:
            return  # it gave a forward instruction: not listened to any more
        if heard.eyebot != self.source:  # under another eye-bot: the last one is "previous"
            self.reference, self.source, self.locked = self.received, heard.eyebot, False
        direction = heard.direction(self.goal, pose)
        self.received = direction
        forward = self.reference is None or abs(wrap(direction - self.reference)) < math.pi / 2
        self._leg(Mode.FOLLOW, direction, self.motion.d)
        self.last_heard_at = pose[:2]
        self.backward, self.locked = not forward, forward

    def _wander(self, seen: FootPerception) -> None:
        """No instruction to follow: head for the closest eye-bot in view, else at random; a
        seek leg that reaches no eye-bot (a wall between) is followed by a random one."""
        if not self._leg_over():
            return
        pose = seen.pose
        target = self._closest_eyebot(seen) if self.mode is not Mode.SEEK or self.may_seek else None
        if target is not None:
            self._leg(Mode.SEEK, wrap(pose[2] + target[1]), target[0])
            self.may_seek = False
            return
        turn = float(self.rng.uniform(-math.pi, math.pi))
        self._leg(Mode.RANDOM, wrap(pose[2] + turn), float(self.rng.uniform(0.5, self.motion.d)))
        self.may_seek = True

    def _leg(self, mode: Mode, heading: float, length: float) -> None:
        """Start driving ``length`` metres towards ``heading``; the leg is given up after twice
        the time it should take (plus the time to turn round)."""
        m = self.motion
        self.mode, self.heading, self.left = mode, heading, length
        self.patience = math.ceil((2.0 * length / m.speed + math.pi / m.turn_rate) / m.dt)

    def _leg_over(self) -> bool:
        return self.left <= 0.0 or self.patience <= 0

    def _closest_eyebot(self, seen: FootPerception) -> tuple[float, float] | None:
        pose = seen.pose
        best: tuple[float, float] | None = None
        for dist, bearing in seen.eyebots:
            if self.last_heard_at is not None:
                where = (
                    pose[0] + dist * math.cos(pose[2] + bearing),
                    pose[1] + dist * math.sin(pose[2] + bearing),
                )
                if distance(where, self.last_heard_at) < self.motion.same_eyebot:
                    continue  # the one it just followed
            if best is None or dist < best[0]:
                best = (dist, bearing)
        return best

    # -- commands --------------------------------------------------------------------------------

    def _drive(self, pose: Pose) -> FootCommand:
        m = self.motion
        error = 0.0 if self.heading is None else wrap(self.heading - pose[2])
        w = max(-m.turn_rate, min(m.turn_rate, 4.0 * error))
        v = m.speed if abs(error) < m.aligned else 0.0
        representative = self.mode is Mode.FOLLOW and not self.backward and v > 0.0
        return FootCommand(v, w, self.goal if representative else None, False)

    def _avoid(self, obstacle: float) -> FootCommand:
        m = self.motion
        if self._turning == 0.0:  # turn away from it, and keep that way until clear
            if abs(obstacle) > HEAD_ON or self.motion.head_on_right:
                self._turning = -1.0 if obstacle >= 0.0 else 1.0
            else:  # straight ahead: either side, by a seeded coin (no side bias)
                self._turning = -1.0 if self.rng.random() < 0.5 else 1.0
        self._escape = m.escape
        v = 0.0 if abs(obstacle) < math.pi / 4 else 0.5 * m.speed
        return FootCommand(v, self._turning * m.turn_rate, None, True)
