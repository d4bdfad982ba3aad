"""The Lévy-search paper's experiment (Sutantyo et al., section V): its setup and sweeps.

The paper gives the arena (20 × 20 "metres", randomly placed obstacles of several sizes), the
speed (60 cm/s), random deployment, 20 trials a point on different arenas, and the measure:
the time until all targets are found. It does not give the sensing and signature ranges, the
obstacle count, the turn phase, nor the numbers behind Fig. 8-9 (only their ordering, L+P < L
< FL, and that the gain from more robots saturates): those below are ours, stated in
:class:`Setup`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from robots.library import LevyParams

#: Fig. 8: search time against the number of targets, 10 robots.
FIG8_TARGETS = (1, 2, 4, 8, 12, 16)
FIG8_ROBOTS = 10
#: Fig. 9: search time against the number of robots, 8 targets.
FIG9_ROBOTS = (1, 2, 5, 10, 15, 20, 30)
FIG9_TARGETS = 8
#: Beyond the paper: search time against the stable index α for L and L+P.
ALPHAS = (0.5, 0.75, 1.0, 1.25, 1.5, 2.0)
ALPHA_ROBOTS = 10
ALPHA_TARGETS = 8
#: Beyond the paper, 8 targets: the fixed walk's step (m) against L and L+P (``step``), L+P
#: taken apart (``parts``: L, L+F, L+S, L+P) and signatures on every walk (``fig4``: FL, FL+S,
#: L, L+S, L+P), at these robot counts.
STEPS = (0.5, 1.0, 1.5, 2.0, 2.5, 4.0, 6.0)
CHECK_ROBOTS = (10, 20, 30)
CHECK_TARGETS = 8
#: The paper's ordering of the mean search times at every point of Fig. 8-9.
ORDER = ("L+P", "L", "FL")


@dataclass(frozen=True)
class Setup:
    """One trial's arena, robots and controller settings (SI units)."""

    size: float = 20.0
    """Side of the square arena (m), V-A."""
    obstacles: int = 12
    obstacle_min: float = 0.5
    obstacle_max: float = 2.5
    walk: LevyParams = field(default_factory=LevyParams)
    """The controller: v = 0.6 m/s (V-A), r_v = 1 m, signatures to 3 m, ρ0 = 1.5 m, …
    (``field`` and ``signatures`` are set by the method)."""
    alpha: float = 1.0
    """Mantegna's stable index of the Lévy steps (1: Viswanathan's μ = 2)."""
    scale: float = 1.0
    """Metres per unit Lévy step."""
    cap: float = 20.0
    """The longest step (m)."""
    fixed: float = 1.0
    """The fixed-length walk's step (m): the Lévy steps' median at α = 1 (scale × 1)."""
    max_time: float = 6000.0
    """A trial that has not found every target by then stops, censored (s)."""

    def tag(self) -> str:
        """The settings that differ from the defaults, except ``alpha`` and ``max_time``
        (which the saved runs record), as ``name=value`` joined by commas ("" if none)."""
        base = Setup()
        diff = [
            f"{k}={getattr(self, k):g}"
            for k in ("size", "obstacles", "obstacle_min", "obstacle_max", "scale", "cap", "fixed")
            if getattr(self, k) != getattr(base, k)
        ]
        diff += [
            f"{k}={getattr(self.walk, k):g}"
            for k in LevyParams.__dataclass_fields__
            if getattr(self.walk, k) != getattr(base.walk, k)
        ]
        return ",".join(diff)
