"""Lévy-flight search with an artificial potential field (Sutantyo et al., sections III-IV).

The controller of eq. 10 and Fig. 4 is :class:`LevyWalker`, a plain seeded object:
``step(sense) -> LevyCommand``. It alternates *move* phases (L(t) = 1: forward at constant v,
for a length drawn from the step generator — :class:`~robots.library.LevySteps` for the Lévy
walk, :class:`~robots.library.FixedSteps` for the fixed-length one) and *turn* phases
(L(t) = 0: in place, at a Gaussian ω). Meanwhile, as in Fig. 4:

* *collision avoidance*: an obstacle ahead on the sonar (or a bump) ends the move phase early
  — the robot "changes its direction earlier than expected" (V-B) — and it turns towards the
  freer side until the way ahead is clear, then starts a new step;
* *potential field routine* (``field``): the repulsion of eq. 9 from the robots within ρ0 —
  their distance and bearing come from range-limited broadcast (or a camera), never from
  ground truth, and obstacles do not repel — bends the heading away from them;
* *catching target*: an unmarked target within the sensing range r_v is marked (the robot's
  message to the target: its LED shows ``mark:<id>`` for a tick) and the walk goes on;
  with ``signatures``, marked targets seen within the signature range repel like robots do,
  so that robots leave found targets to search elsewhere.

:data:`METHODS` names the paper's three walks (FL, L, L+P), :data:`WALKS` those and their parts
(L+F, L+S, FL+S: the field or the signatures alone); :func:`walker` builds one, and
:func:`levy_search` runs one on a robot's HAL.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from robots._robot import Robot
from robots.hal import MARK, MARKED, Hardware, Sighting

from ._geometry import clip, wrap
from ._levy_steps import FixedSteps, LevySteps

METHODS = ("FL", "L", "L+P")
"""The paper's walks: fixed-length (FL), Lévy (L), Lévy with potential field and signatures
(L+P)."""

WALKS: dict[str, tuple[bool, bool, bool]] = {
    "FL": (False, False, False),
    "L": (True, False, False),
    "L+P": (True, True, True),
    "L+F": (True, True, False),
    "L+S": (True, False, True),
    "FL+S": (False, False, True),
}
"""Every walk :func:`walker` builds, as (Lévy steps, ``field``, ``signatures``): the paper's
three, and L+P taken apart — L+F (the robots' mutual repulsion alone), L+S (the found
targets' signatures alone) — and FL+S (the fixed-length walk with signatures: with L+S and
L+P, the reading of Fig. 4, whose controller leaves a signature on every walk's finds)."""

_EPS = 1e-9  # metres or seconds: a phase that has this little left is over
RETRY = 10
"""Ticks after which a target still unmarked gets the mark message again."""

Neighbour = tuple[float, float]
"""(distance m, bearing rad in the robot's frame) of another robot."""


class Steps(Protocol):
    """Where a walk's step lengths come from."""

    def draw(self) -> float:
        """The next step length (m)."""
        ...


@dataclass(frozen=True, slots=True)
class LevySense:
    """What the controller senses in one tick."""

    dt: float
    """Seconds per tick."""
    sonar: tuple[float, ...] = ()
    """Sonar ranges from the rim (m)."""
    angles: tuple[float, ...] = ()
    """Sonar ray directions relative to the heading (rad)."""
    bump: bool = False
    neighbours: tuple[Neighbour, ...] = ()
    """Robots heard or seen: (distance, bearing)."""
    targets: tuple[Sighting, ...] = ()
    """Targets seen (kind ``target``), status ``marked`` once marked."""


@dataclass(frozen=True, slots=True)
class LevyCommand:
    """What the controller does for one tick: drive (v, ω), and mark a target or not."""

    v: float
    w: float
    state: str
    """The Fig. 4 state: ``move``, ``field``, ``turn``, ``avoid`` or ``catch``."""
    mark: str | None = None


@dataclass(frozen=True)
class LevyParams:
    """The controller's settings (SI units). Defaults: the experiment's robots (V-A)."""

    speed: float = 0.6
    """v of eq. 10: 60 cm/s (V-A)."""
    turn_time: float = 1.0
    """Length of a zero phase of L(t) (s)."""
    turn_sd: float = 1.5
    """Standard deviation of the Gaussian ω of a turn phase (rad/s)."""
    max_turn: float = 2.0
    sense_range: float = 1.0
    """r_v: an unmarked target this near is found (m)."""
    avoid_range: float = 0.35
    """An obstacle this near ahead (sonar, from the rim) ends the step (m)."""
    avoid_cone: float = 0.8
    """Sonar rays within ± this of the heading look ahead (rad)."""
    field: bool = False
    """Repulsion among robots (eq. 8-9)."""
    rho0: float = 1.5
    """ρ0 of eq. 8-9 (m)."""
    k_rep: float = 1.0
    """k_rep of eq. 8-9."""
    signatures: bool = False
    """Marked targets repel (V-B)."""
    signature_range: float = 3.0
    """How far a marked target's signature reaches (m), wider than ``sense_range``."""
    k_sig: float = 10.0
    """k_rep of a signature."""
    own_signatures: bool = False
    """Whether a robot is repelled by the targets it marked itself too. The paper has the
    signature turn away "other robots" (IV-A, V-B); the finder, still next to the target it
    just marked, would be turned back into the area it came from (with it, one robot took
    1843 s instead of L's 1446 s to find 8 targets; see results/README.md)."""
    steer_gain: float = 2.0
    """Turn rate per radian between the heading and the field's direction (1/s)."""


def repulsion(neighbours: Sequence[Neighbour], k_rep: float, rho0: float) -> tuple[float, float]:
    """The repulsive force of eq. 9 summed over ``neighbours``, in the robot's frame.

    F = k_rep (1/ρ - 1/ρ0) (1/ρ²) (q - q_neighbour)/ρ for ρ ≤ ρ0, and 0 beyond: Khatib's
    potential, which eq. 8-9 cite. The paper prints the two conditions the other way round (a
    force for ρ ≥ ρ0, none inside), which would repel only distant robots, pull (the factor
    is negative) and vanish where robots are close; this is the physically meaningful one.
    (Eq. 8 also drops Khatib's square: eq. 9 is the gradient of U = ½ k_rep (1/ρ - 1/ρ0)².)
    """
    fx = fy = 0.0
    for rho, bearing in neighbours:
        if rho <= 0.0 or rho > rho0:
            continue
        magnitude = k_rep * (1.0 / rho - 1.0 / rho0) / rho**2
        fx -= magnitude * math.cos(bearing)
        fy -= magnitude * math.sin(bearing)
    return fx, fy


def levy_sense(
    dt: float,
    sonar: Sequence[float],
    angles: Sequence[float],
    bump: bool,
    sightings: Sequence[Sighting],
    neighbours: Sequence[Neighbour],
) -> LevySense:
    """A :class:`LevySense` from plain readings (the targets among ``sightings``)."""
    targets = tuple(s for s in sightings if s.kind == "target")
    return LevySense(dt, tuple(sonar), tuple(angles), bump, tuple(neighbours), targets)


def hal_sense(hw: Hardware, neighbours: Sequence[Neighbour]) -> LevySense:
    """A :class:`LevySense` from a robot's HAL and the neighbours it heard."""
    sonar = hw.sonar
    return levy_sense(
        hw.clock.tick_period,
        sonar.ranges() if sonar is not None else (),
        sonar.angles if sonar is not None else (),
        hw.bumper.pressed() if hw.bumper is not None else False,
        hw.camera.sightings() if hw.camera is not None else (),
        neighbours,
    )


@dataclass
class LevyWalker:
    """The controller of eq. 10 and Fig. 4 (see the module docstring)."""

    steps: Steps
    rng: np.random.Generator
    params: LevyParams = field(default_factory=LevyParams)
    state: str = "move"
    left: float = 0.0
    """Metres left in this move phase, or seconds left in this turn phase."""
    omega: float = 0.0
    marked: set[str] = field(default_factory=set)
    """Targets this robot sent a mark to."""
    ticks: int = 0
    _tried: dict[str, int] = field(default_factory=dict, repr=False)
    avoid_dir: float = 1.0
    phases: int = 0
    """Move phases begun."""

    def __post_init__(self) -> None:
        self._new_step()

    def _new_step(self) -> None:
        self.state, self.left = "move", self.steps.draw()
        self.phases += 1

    def _ahead(self, s: LevySense) -> float:
        near = [
            r
            for r, a in zip(s.sonar, s.angles, strict=False)
            if abs(wrap(a)) <= self.params.avoid_cone
        ]
        return min(near, default=math.inf)

    def _free_side(self, s: LevySense) -> float:
        left = sum(
            r * math.sin(a) for r, a in zip(s.sonar, s.angles, strict=False) if math.sin(a) > 1e-6
        )
        right = sum(
            -r * math.sin(a) for r, a in zip(s.sonar, s.angles, strict=False) if math.sin(a) < -1e-6
        )
        if left == right:
            return 1.0 if self.rng.random() < 0.5 else -1.0
        return 1.0 if left > right else -1.0

    def force(self, s: LevySense) -> tuple[float, float]:
        """The field's force on the robot now: eq. 9 from robots (``field``) plus the
        signatures (``signatures``) of the marked targets — other robots' finds, unless
        ``own_signatures`` — in the robot's frame."""
        p = self.params
        fx = fy = 0.0
        if p.field:
            fx, fy = repulsion(s.neighbours, p.k_rep, p.rho0)
        if p.signatures:
            sig = [
                (t.range, t.bearing)
                for t in s.targets
                if t.status == MARKED and (p.own_signatures or t.id not in self.marked)
            ]
            gx, gy = repulsion(sig, p.k_sig, p.signature_range)
            fx, fy = fx + gx, fy + gy
        return fx, fy

    def step(self, s: LevySense) -> LevyCommand:
        """The command for the next tick."""
        p = self.params
        self.ticks += 1
        for t in s.targets:  # Catching target (again if the last message was not heard)
            if t.status == MARKED or t.range > p.sense_range:
                continue
            if self.ticks - self._tried.get(t.id, -RETRY) >= RETRY:
                self._tried[t.id] = self.ticks
                self.marked.add(t.id)
                return LevyCommand(0.0, 0.0, "catch", t.id)
        if self.state == "avoid":
            if not s.bump and self._ahead(s) > 1.5 * p.avoid_range:
                self._new_step()
            else:
                return LevyCommand(0.0, self.avoid_dir * p.max_turn, "avoid")
        if self.state == "turn":
            if self.left > _EPS:
                self.left -= s.dt
                return LevyCommand(0.0, self.omega, "turn")
            self._new_step()
        # move phase (L(t) = 1): Collision Avoidance, then the Potential Field Routine
        if s.bump or self._ahead(s) < p.avoid_range:
            self.state, self.avoid_dir = "avoid", self._free_side(s)
            return LevyCommand(0.0, self.avoid_dir * p.max_turn, "avoid")
        self.left -= p.speed * s.dt
        if self.left <= _EPS:
            self.state, self.left = "turn", p.turn_time
            self.omega = clip(float(self.rng.normal(0.0, p.turn_sd)), -p.max_turn, p.max_turn)
        fx, fy = self.force(s)
        if fx == 0.0 and fy == 0.0:
            return LevyCommand(p.speed, 0.0, "move")
        turn = clip(p.steer_gain * math.atan2(fy, 1.0 + fx), -p.max_turn, p.max_turn)
        return LevyCommand(p.speed, turn, "field")


def walker(
    method: str,
    rng: np.random.Generator,
    *,
    alpha: float = 1.0,
    scale: float = 1.0,
    cap: float = 20.0,
    fixed: float = 1.0,
    params: LevyParams | None = None,
) -> LevyWalker:
    """A walk by name (:data:`WALKS`): ``FL`` steps of ``fixed`` m; ``L`` Lévy steps of
    stable index ``alpha``, ``scale`` m a unit, at most ``cap`` m; ``L+P`` the same with the
    field among robots and the targets' signatures switched on; ``L+F``, ``L+S`` and ``FL+S``
    with the field only, the signatures only, and FL with the signatures."""
    if method not in WALKS:
        raise ValueError(f"unknown method {method!r}; choose from {', '.join(WALKS)}")
    levy, on_field, on_signatures = WALKS[method]
    base = replace(params or LevyParams(), field=on_field, signatures=on_signatures)
    steps: Steps = LevySteps(rng, alpha=alpha, scale=scale, cap=cap) if levy else FixedSteps(fixed)
    return LevyWalker(steps, rng, base)


async def levy_search(
    robot: Robot,
    walk: LevyWalker,
    neighbours: Callable[[], Sequence[Neighbour]] = tuple,
    terminator: Callable[[], bool] | None = None,
    on_mark: Callable[[str, float], None] | None = None,
) -> set[str]:
    """Run ``walk`` on the robot's HAL until ``terminator`` returns True (polled every tick).

    ``neighbours()`` gives the robots heard this tick (from range-limited broadcast); a
    target is marked by showing ``mark:<id>`` on the LED for one tick, and ``on_mark(id,
    time)`` is called once the camera shows it marked, with the hardware time. Returns the
    targets this robot sent a mark to; the motors are stopped on the way out.
    """
    hw = robot.hw
    showing = False
    try:
        while terminator is None or not terminator():
            cmd = walk.step(hal_sense(hw, neighbours()))
            if hw.led is not None and (cmd.mark is not None or showing):
                hw.led.show("" if cmd.mark is None else MARK + cmd.mark)
                showing = cmd.mark is not None
            hw.drive.set_velocity(cmd.v, cmd.w)
            await hw.clock.tick()
            if cmd.mark is not None and on_mark is not None and _shows_marked(hw, cmd.mark):
                on_mark(cmd.mark, hw.clock.now())
        return set(walk.marked)
    finally:
        hw.drive.stop()


def _shows_marked(hw: Hardware, target: str) -> bool:
    seen = hw.camera.sightings() if hw.camera is not None else ()
    return any(t.id == target and t.status == MARKED for t in seen)
