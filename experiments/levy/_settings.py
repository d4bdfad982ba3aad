"""What a Lévy-search run does and reports: one frozen record, made from the command line."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .._saved import Executor
from ._paper import CHECK_ROBOTS, STEPS, Setup


@dataclass(frozen=True)
class Point:
    """One point of a sweep: a method on ``robots`` robots, ``targets`` targets, index α;
    ``fixed``: the fixed walk's step (m) where it is not the settings' (``Setup.fixed``)."""

    method: str
    robots: int
    targets: int
    alpha: float
    fixed: float | None = None

    @property
    def name(self) -> str:
        """The point's file name stem (``L+P_r10_t8_a1``; ``FL_r10_t8_a1_f2.5`` with its own
        step)."""
        step = "" if self.fixed is None else f"_f{self.fixed:g}"
        return f"{self.method}_r{self.robots}_t{self.targets}_a{self.alpha:g}{step}"


@dataclass(frozen=True)
class LevySettings:
    """The sweeps to run (every trial's seed derives from ``seed``) and what to print.

    ``save``: the directory of per-point JSON-lines files, appended as runs finish and read
    back so that a later run with the same seed only adds the runs missing (None: keep
    nothing); ``out``: the figures' directory (None: none), ``format`` theirs; ``json``: end
    with one JSON line of every run. ``steps``: the fixed walk's steps of the ``step`` sweep;
    ``check_robots``: the robot counts of the ``step``, ``parts`` and ``fig4`` sweeps.
    """

    seed: int
    runs: int
    sweeps: tuple[str, ...]
    methods: tuple[str, ...]
    targets: tuple[int, ...]
    robots: tuple[int, ...]
    alphas: tuple[float, ...]
    steps: tuple[float, ...] = STEPS
    check_robots: tuple[int, ...] = CHECK_ROBOTS
    workers: int = 2
    executor: Executor = field(default_factory=Executor)
    setup: Setup = field(default_factory=Setup)
    save: Path | None = None
    out: Path | None = None
    format: str = "png"
    json: bool = False
    progress: bool = True
