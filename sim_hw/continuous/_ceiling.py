"""The ceiling layer: eye-bots above a :class:`World`, and the devices that link them to the
foot-bots below (Ducatelle et al., sections 2 and 4.3).

Eye-bots hang still from the ceiling, so they are not bodies of the physics at all: nothing on
the ground can touch them. Every distance between the layers is horizontal (the ceiling is
flat). Per tick (:meth:`Ceiling.sense`, after :meth:`World.step`), from the ground truth:

* an eye-bot's downward camera sees the foot-bots within ``view`` metres of the point below it:
  where each one's top beacon is and where its front LED is (``FOOT_LED`` ahead of the beacon)
  when that is on, in the eye-bot's frame, with the colours its LED status shows
  (:mod:`robots.stigmergic` reads them);
* its infrared broadcast is a cone: it reaches the foot-bots within ``cone`` metres; a foot-bot
  under several cones (they should not overlap) hears the nearest eye-bot only;
* a foot-bot's upward camera reads θ0 of that eye-bot (its red-front / blue-back LEDs) as an
  angle in the foot-bot's frame;
* a foot-bot's omnidirectional camera sees the eye-bots within ``omni_range``, as distance and
  bearing in its frame.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from robots.stigmergic import read_leds

from ._spec import EyeBotSpec, Vec
from ._world import World

FOOT_LED = 0.08
"""How far ahead of a foot-bot's beacon its front LED is (m): its radius, about."""


@dataclass(frozen=True, slots=True)
class Below:
    """One foot-bot as an eye-bot's camera sees it: beacon and front LED positions in the
    eye-bot's frame (metres; ``front`` None when that LED is off) and the LED status string
    (:func:`robots.stigmergic.read_leds` says what its colours mean)."""

    robot: str
    beacon: Vec
    front: Vec | None
    led: str


class Ceiling:
    """Eye-bots above ``world``; :meth:`sense` after each world step, then read the devices."""

    def __init__(
        self,
        world: World,
        eyebots: Sequence[EyeBotSpec],
        omni_range: float = 3.0,
    ) -> None:
        ids = [e.id for e in eyebots]
        if len(set(ids)) != len(ids):
            raise ValueError("eye-bot ids must be unique")
        self.world = world
        self.eyebots = {e.id: e for e in eyebots}
        self.omni_range = omni_range
        self._ids = ids
        self._xy = np.array([e.center for e in eyebots], dtype=float).reshape(-1, 2)
        self._theta = np.array([e.heading for e in eyebots], dtype=float)
        self._view = np.array([e.view for e in eyebots], dtype=float)
        self._cone = np.array([e.cone for e in eyebots], dtype=float)
        self._index = {eid: j for j, eid in enumerate(ids)}
        self._robots: list[str] = []
        self._row: dict[str, int] = {}
        self._pose = np.zeros((0, 3))
        self._dist = np.zeros((0, len(ids)))
        self._in_view: list[list[int]] = [[] for _ in ids]  # by eye-bot: the rows it sees
        self._over: list[int | None] = []  # by row: the eye-bot whose cone reaches it
        self._omni: list[list[int]] = []  # by row: the eye-bots in omni range, nearest first

    def sense(self, robots: Sequence[str] | None = None) -> None:
        """Take the foot-bots' poses of this tick (``robots``: which, default all)."""
        names = sorted(self.world.robots) if robots is None else list(robots)
        self._robots = names
        self._pose = np.array([self.world.pose(r) for r in names], dtype=float).reshape(-1, 3)
        self._row = {r: i for i, r in enumerate(names)}
        delta = self._pose[:, None, :2] - self._xy[None, :, :]
        self._dist = dist = np.hypot(delta[..., 0], delta[..., 1])
        # what every device of the tick reads, worked out once for all (most eye-bots see
        # nobody): the rows each eye-bot sees, in row order, and the nearest cone over each row
        self._in_view = [[] for _ in self._ids]
        eyes, rows = np.nonzero((dist <= self._view).T)
        for j, i in zip(eyes.tolist(), rows.tolist(), strict=True):
            self._in_view[j].append(i)
        self._over = [None] * len(names)
        if len(self._ids):
            cones = np.where(dist <= self._cone, dist, np.inf)
            nearest = np.argmin(cones, axis=1)
            for i in np.flatnonzero(np.isfinite(cones[np.arange(len(names)), nearest])).tolist():
                self._over[i] = int(nearest[i])
        near = dist <= self.omni_range
        order = np.argsort(np.where(near, dist, np.inf), axis=1, kind="stable")
        self._omni = [o[:k] for o, k in zip(order.tolist(), near.sum(axis=1).tolist(), strict=True)]

    # -- the eye-bot's camera -----------------------------------------------------------------

    def camera(self, eyebot: str) -> list[Below]:
        """The foot-bots an eye-bot sees, in its frame."""
        j = self._index[eyebot]
        rows = self._in_view[j]
        if not rows:
            return []
        ex, ey = self._xy[j]
        c, s = math.cos(self._theta[j]), math.sin(self._theta[j])
        out = []
        for i in rows:
            rid = self._robots[i]
            x, y, heading = self._pose[i]
            led = self.world.robots[rid].led
            beacon = _frame(x - ex, y - ey, c, s)
            front = None
            shown = read_leds(led)
            if shown is not None and shown[1] is not None:
                fx, fy = x + FOOT_LED * math.cos(heading), y + FOOT_LED * math.sin(heading)
                front = _frame(fx - ex, fy - ey, c, s)
            out.append(Below(rid, beacon, front, led))
        return out

    # -- the foot-bot's devices ---------------------------------------------------------------

    def above(self, robot: str) -> tuple[str, float] | None:
        """The eye-bot whose broadcast reaches ``robot`` (the nearest if several do) and its θ0
        as the upward camera reads it (radians in the foot-bot's frame); None under none."""
        i = self._row[robot]
        j = self._over[i]
        if j is None:
            return None
        return self._ids[j], _wrap(float(self._theta[j] - self._pose[i, 2]))

    def omni(self, robot: str) -> list[tuple[float, float]]:
        """(distance, bearing) of the eye-bots within ``omni_range``, nearest first."""
        i = self._row[robot]
        x, y, heading = self._pose[i]
        dist = self._dist[i]
        near = self._omni[i]
        return [
            (float(dist[j]), _wrap(math.atan2(self._xy[j, 1] - y, self._xy[j, 0] - x) - heading))
            for j in near
        ]

    def under(self) -> Mapping[str, str | None]:
        """Which eye-bot's cone each foot-bot is in (None: none), for statistics."""
        out: dict[str, str | None] = {}
        for rid, j in zip(self._robots, self._over, strict=True):
            out[rid] = None if j is None else self._ids[j]
        return out


def _frame(dx: float, dy: float, c: float, s: float) -> Vec:
    return (c * dx + s * dy, -s * dx + c * dy)


def _wrap(angle: float) -> float:
    return math.remainder(angle, 2.0 * math.pi)
