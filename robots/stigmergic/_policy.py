"""An eye-bot's stochastic policies (Ducatelle et al., section 4.2).

A policy is 12 positive preferences, one per direction π/6 apart, all 1/12 at the start. An
increase adds ``c_a``, a decrease multiplies by ``c_m`` (eq. 1). A draw takes, with probability
``q``, the direction of highest preference, and otherwise one drawn in proportion to the
preferences.

Choices the paper leaves open, taken here:

* directions are counter-clockwise angles in the eye-bot's own frame, index 0 along its
  reference direction θ0; an angle belongs to the nearest of the 12 (half-way angles go to the
  higher index, as ``round`` to even would make them depend on the index);
* when several directions share the highest preference (at the start all 12 do), the greedy
  draw takes one of them at random, not always the first: an untrained eye-bot then sends
  uniformly random instructions, which is what "at first, eye-bot policies are uniform, and
  foot-bots perform random exploration" describes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from robots.library._geometry import wrap

DIRECTIONS = 12
"""Discrete navigation directions."""
SPACING = 2.0 * math.pi / DIRECTIONS
"""Radians between two neighbouring directions (π/6)."""


def direction_index(angle: float) -> int:
    """The index of the discrete direction nearest to ``angle`` (radians, any value)."""
    return math.floor(angle / SPACING + 0.5) % DIRECTIONS


def direction_angle(index: int) -> float:
    """The angle of direction ``index``, in (-π, π]."""
    return wrap((index % DIRECTIONS) * SPACING)


@dataclass(frozen=True)
class Learning:
    """The learning constants of eq. 1 and the draw (section 5: c_a = 0.5, c_m = 0.99, q = 0.5)."""

    c_a: float = 0.5
    c_m: float = 0.99
    q: float = 0.5

    def __post_init__(self) -> None:
        if not self.c_a > 0.0:
            raise ValueError(f"c_a must be > 0, not {self.c_a}")
        if not 0.0 <= self.c_m < 1.0:
            raise ValueError(f"c_m must be in [0, 1), not {self.c_m}")
        if not 0.0 <= self.q <= 1.0:
            raise ValueError(f"q must be in [0, 1], not {self.q}")


@dataclass
class Policy:
    """Preferences for the 12 directions (a copy of the array is :attr:`preferences`)."""

    prefs: np.ndarray = field(default_factory=lambda: np.full(DIRECTIONS, 1.0 / DIRECTIONS))

    @property
    def preferences(self) -> tuple[float, ...]:
        """The 12 preferences, index 0 first."""
        return tuple(float(p) for p in self.prefs)

    def increase(self, index: int, c_a: float, weight: float = 1.0) -> None:
        """Eq. 1, an increase: add ``c_a`` (times ``weight``, 1 in the paper)."""
        self.prefs[index % DIRECTIONS] += c_a * weight

    def decrease(self, index: int, c_m: float) -> None:
        """Eq. 1, a decrease: multiply by ``c_m``."""
        self.prefs[index % DIRECTIONS] *= c_m

    def best(self) -> int:
        """The index of the highest preference (the first of several equal ones)."""
        return int(np.argmax(self.prefs))

    def draw(self, rng: np.random.Generator, q: float) -> int:
        """With probability ``q`` the best direction (a random one of equal bests), else one
        drawn in proportion to the preferences."""
        if rng.random() < q:
            top = np.flatnonzero(self.prefs == self.prefs.max())
            return int(top[0] if len(top) == 1 else rng.choice(top))
        # what ``rng.choice(DIRECTIONS, p=prefs / total)`` does, without its checks: the same
        # one uniform draw and the same index (the tests compare the two)
        cdf = (self.prefs / float(self.prefs.sum())).cumsum()
        cdf /= cdf[-1]
        return int(cdf.searchsorted(rng.random(), side="right"))
