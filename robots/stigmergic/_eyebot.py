"""The eye-bot (Ducatelle et al., sections 4.1–4.3): observe foot-bots, learn, instruct.

An eye-bot hangs from the ceiling. Each time step it looks at the foot-bots in its camera's
view (:class:`FootBotSeen`: where their top beacon is, its colour, and where their front LED is,
if it is on, and its colour) and updates its two policies (eq. 1):

* a foot-bot going to the target comes from the source: ``P_s`` up and ``P_t`` down for the
  direction θ_f it comes from (and the other way round for one going to the source). θ_f is read
  off the two LEDs: the foot-bot moves from its beacon towards its front LED, so it comes from
  the opposite direction. Only a foot-bot *coming towards* the eye-bot counts (sections
  4.1–4.2: θ_f is where it comes from); read from the view: its heading (beacon to front LED)
  is within ``APPROACH`` (±π/2) of the bearing from its beacon to the middle of the view, i.e.
  its distance to the eye-bot is shrinking. One seen within ``CENTRE`` of the middle has no
  such bearing and counts for nothing. A foot-bot leaving after an instruction would show the
  eye-bot its own instruction reflected (an echo); the old reading, every foot-bot in view
  approaching or leaving, is ``EyeBot(reading=Reading.ANY)``;
* a foot-bot avoiding an obstacle (its beacon's colour says so) marks the direction where it is
  seen as blocked: both policies down there.

Then it draws θ_s and θ_t (:meth:`Policy.draw`) and broadcasts them; they are angles relative to
its reference direction θ0, which its red front and blue back LEDs show to foot-bots below.

Choices the paper leaves open, taken here: every foot-bot in view updates the policies once per
time step (the paper says "when an eye-bot observes a foot-bot", at "discrete time steps"); a
foot-bot whose front LED is off updates nothing unless its beacon says it is avoiding. Beyond the
paper (its future work, section 8), :meth:`EyeBot.observe` takes a ``weight`` per foot-bot that
scales its increases, from the trip time the foot-bot reports (:func:`trip_weight`).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from robots.library._geometry import Point

from ._policy import Learning, Policy, direction_angle, direction_index

APPROACH = math.pi / 2
"""A foot-bot comes towards the eye-bot when its heading is within this angle of the bearing
from it to the middle of the view (π/2: its distance to the eye-bot is shrinking)."""
CENTRE = 0.05
"""A foot-bot whose beacon is this close to the middle of the view (m) is neither coming nor
going."""


class Reading(enum.Enum):
    """Which foot-bots in view give a θ_f: those coming towards the eye-bot (the paper's
    reading, the default) or every one with its front LED on (the old reading)."""

    APPROACHING = "approaching"
    ANY = "any"


class Goal(enum.Enum):
    """Where a foot-bot is going: shown by its front LED's colour."""

    TARGET = "target"
    SOURCE = "source"

    @property
    def other(self) -> Goal:
        """The goal after this one is reached."""
        return Goal.SOURCE if self is Goal.TARGET else Goal.TARGET


@dataclass(frozen=True)
class FootBotSeen:
    """One foot-bot in an eye-bot's view, in the eye-bot's frame (metres, x along θ0).

    ``front`` is where its front LED is, None when the LED is off; ``goal`` is what its colour
    says; ``avoiding`` is what the beacon's colour says.
    """

    beacon: Point
    avoiding: bool = False
    front: Point | None = None
    goal: Goal | None = None
    weight: float = 1.0

    def came_from(self) -> float | None:
        """θ_f: the direction it comes from, or None when its front LED is off."""
        if self.front is None:
            return None
        heading = math.atan2(self.front[1] - self.beacon[1], self.front[0] - self.beacon[0])
        return heading + math.pi

    def coming_towards(self, within: float = APPROACH) -> bool:
        """Whether it is coming towards the eye-bot: its front LED on, its heading within
        ``within`` of the bearing from its beacon to the middle of the view, and its beacon
        not within :data:`CENTRE` of that middle."""
        if self.front is None or math.hypot(*self.beacon) < CENTRE:
            return False
        heading = math.atan2(self.front[1] - self.beacon[1], self.front[0] - self.beacon[0])
        inward = math.atan2(-self.beacon[1], -self.beacon[0])
        return abs(math.remainder(heading - inward, 2.0 * math.pi)) < within

    def seen_at(self) -> float:
        """The direction in which it is seen."""
        return math.atan2(self.beacon[1], self.beacon[0])


@dataclass(frozen=True)
class Instruction:
    """What an eye-bot broadcasts: θ_s and θ_t, radians relative to its reference θ0."""

    to_source: float
    to_target: float

    def towards(self, goal: Goal) -> float:
        """The direction for a foot-bot going to ``goal``."""
        return self.to_target if goal is Goal.TARGET else self.to_source


@dataclass
class EyeBot:
    """An eye-bot's learning and instructions; its randomness from ``rng``."""

    rng: np.random.Generator
    learning: Learning = field(default_factory=Learning)
    to_source: Policy = field(default_factory=Policy)
    to_target: Policy = field(default_factory=Policy)
    frozen: bool = False  # pre-programmed (:meth:`show_shortest`): observations change nothing
    reading: Reading = Reading.APPROACHING

    def step(self, seen: Sequence[FootBotSeen]) -> Instruction:
        """One time step: learn from the foot-bots in view, then draw the instruction."""
        self.observe(seen)
        return self.instruct()

    def observe(self, seen: Sequence[FootBotSeen]) -> None:
        """Update both policies from what the camera sees (eq. 1)."""
        if self.frozen:
            return
        c_a, c_m = self.learning.c_a, self.learning.c_m
        for foot in seen:
            if foot.avoiding:
                i = direction_index(foot.seen_at())
                self.to_source.decrease(i, c_m)
                self.to_target.decrease(i, c_m)
                continue
            came_from = foot.came_from()
            if came_from is None or foot.goal is None:
                continue
            if self.reading is Reading.APPROACHING and not foot.coming_towards():
                continue
            i = direction_index(came_from)
            towards, away = (
                (self.to_source, self.to_target)
                if foot.goal is Goal.TARGET
                else (self.to_target, self.to_source)
            )
            towards.increase(i, c_a, foot.weight)
            away.decrease(i, c_m)

    def instruct(self) -> Instruction:
        """Draw θ_s and θ_t from the policies."""
        q = self.learning.q
        return Instruction(
            to_source=direction_angle(self.to_source.draw(self.rng, q)),
            to_target=direction_angle(self.to_target.draw(self.rng, q)),
        )

    def show_shortest(self, to_source: float, to_target: float) -> None:
        """Pre-program the policies (the paper's t_s): always instruct these directions."""
        for policy, angle in ((self.to_source, to_source), (self.to_target, to_target)):
            policy.prefs[:] = 0.0
            policy.prefs[direction_index(angle)] = 1.0
        self.learning = Learning(self.learning.c_a, self.learning.c_m, q=1.0)
        self.frozen = True


def trip_weight(trip: float, reference: float) -> float:
    """Beyond the paper: how much a foot-bot's observation counts, from how long its trip has
    taken so far (``trip``) against a reference trip time: 1 at the reference, more for faster
    trips, less for slower ones (``reference / trip``, within [0.25, 4])."""
    if trip <= 0.0 or reference <= 0.0:
        return 1.0
    return min(4.0, max(0.25, reference / trip))
