"""`mover experiment levy`: Lévy-flight search with a potential field, in-process.

Sutantyo et al., section V. Each trial builds a 20 × 20 m arena with seeded random obstacles,
places the targets (passive beacons, found within the sensing range r_v = 1 m and marked by
the finder) and the robots at random, and runs one of three walks on every robot — FL
(fixed-length random walk), L (Lévy walk, Mantegna's stable index α = 1: Viswanathan's
inverse-square law) and L+P (Lévy walk, the robots' mutual repulsion of eq. 9 from what they
hear by range-limited broadcast, and found targets' signatures repelling within 3 m) — until
every target is marked; the search time is when the last one was. Sweeps: ``fig8`` (search
time vs targets, 10 robots), ``fig9`` (vs robots, 8 targets) and ``alpha`` (vs α for L and
L+P, held against the theory's prediction for destructive search); beyond the paper, at 8
targets and 10, 20, 30 robots: ``step`` (FL at steps of 0.5-6 m against L and L+P: does
L < FL rest on FL's step?), ``parts`` (L+P taken apart: L+F the field among robots only, L+S
the signatures only) and ``fig4`` (signatures on every walk, FL+S beside L+S and L+P, as the
paper's Fig. 4 controller reads). Runs go to a pool of worker processes; every run's seeds
derive from the master seed (printed) and the run index, the same arenas for every method.
Per-point runs are saved as JSON lines and read back (``--save``), so a later run adds trials.
"""

from ._checks import cauchy_steps, checks_report, step_stats, step_table
from ._cli import register, run, settings
from ._paper import ALPHAS, FIG8_TARGETS, FIG9_ROBOTS, ORDER, Setup
from ._report import paired, saturation, table, theory
from ._settings import LevySettings, Point
from ._sweep import CHECKS, SWEEPS, points, run_points
from ._trial import arena, heard, run_trial, run_world, world_data

__all__ = [
    "ALPHAS",
    "CHECKS",
    "FIG8_TARGETS",
    "FIG9_ROBOTS",
    "ORDER",
    "SWEEPS",
    "LevySettings",
    "Point",
    "Setup",
    "arena",
    "cauchy_steps",
    "checks_report",
    "heard",
    "paired",
    "points",
    "register",
    "run",
    "run_points",
    "run_trial",
    "run_world",
    "saturation",
    "settings",
    "step_stats",
    "step_table",
    "table",
    "theory",
    "world_data",
]
