"""The points of the eye-bot experiment's figures, their runs on a pool, and the saved runs.

A point is an arena (``cluttered`` or ``corridor-r<ratio>``), a number of foot-bots, and how
the eye-bots work (learning, pre-programmed with the shortest way: ``shortest``, or learning
with the trip-time weights: ``weigh``). Run k of every point has the same seed (derived from
the master seed and k), so that the ways of working are compared on the same starts.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from robots.stigmergic import Motion, Reading
from sim_hw.continuous import TICK

from .. import _runner
from .._saved import Executor, Made, Record
from ._arena import Arena, cluttered, corridors
from ._trial import Settings, run

FIGURES = ("fig2", "fig3", "fig4", "fig5", "beyond")
FIG2_FOOTBOTS = (1, 2, 5, 10, 15, 20)
FIG3_RATIOS = (1.0, 1.5, 2.0)
FIG3_FOOTBOTS = 15
FIG4_FOOTBOTS = (1, 5, 10, 15, 20, 25, 30)
FIG5_FOOTBOTS = (10, 20, 30)
BEYOND_FOOTBOTS = (20, 30)
MIRRORED = "-mirrored"
"""The suffix of a mirrored double corridor's name (Fig. 3)."""
DEPLOY_EVERY = 30.0
"""Fig. 3-5: one foot-bot deployed every 30 s."""


@dataclass(frozen=True)
class Point:
    """One point: an arena, a number of foot-bots, the eye-bots' way of working."""

    arena: str
    footbots: int
    eyebots: str = "learning"  # or "shortest", "weigh"
    deploy_every: float = 0.0

    @property
    def name(self) -> str:
        """The point's file name stem (``cluttered_n10_learning``)."""
        deploy = f"_d{self.deploy_every:g}" if self.deploy_every else ""
        return f"{self.arena}_n{self.footbots}_{self.eyebots}{deploy}"


@dataclass(frozen=True)
class EyebotSettings:
    """What to run: the figures, runs per point, the master seed, workers, where to save."""

    seed: int
    runs: int
    figures: tuple[str, ...] = ("fig2",)
    duration: float = 3000.0
    workers: int = 2
    executor: Executor = field(default_factory=Executor)
    save: Path | None = None
    progress: bool = True
    saved_only: bool = False  # report the saved runs, make none
    period: float = TICK  # the eye-bots' step (the old reading: 1 s)
    reading: Reading = Reading.APPROACHING  # which foot-bots give θ_f (old: Reading.ANY)
    head_on_right: bool = False  # the old avoidance: straight ahead always passed right
    over_walls: bool = False  # the old cluttered arena: eye-bots over its walls too
    footbots: tuple[int, ...] = ()  # only these numbers of foot-bots (all: empty)
    ways: tuple[str, ...] = ()  # only these ways of the eye-bots (all: empty)

    def old(self) -> list[str]:
        """The old readings asked for, as ``name=value`` (none: the new defaults)."""
        return [
            *([f"period={self.period:g}"] if self.period != TICK else []),
            *([f"reading={self.reading.value}"] if self.reading is not Reading.APPROACHING else []),
            *(["head-on=right"] if self.head_on_right else []),
            *(["over-walls"] if self.over_walls else []),
        ]

    def chosen(self, pts: list[Point]) -> list[Point]:
        """``pts`` narrowed to :attr:`footbots` and :attr:`ways`."""
        return [
            p
            for p in pts
            if (not self.footbots or p.footbots in self.footbots)
            and (not self.ways or p.eyebots in self.ways)
        ]


def points(figure: str) -> list[Point]:
    """The points of one figure (Fig. 5 is drawn from Fig. 4's runs)."""
    if figure == "fig2":
        return [
            Point("cluttered", n, way) for n in FIG2_FOOTBOTS for way in ("learning", "shortest")
        ]
    if figure == "fig3":  # and each ratio mirrored (the shorter corridor on the left)
        return [
            Point(_corridor(r) + mirror, FIG3_FOOTBOTS, deploy_every=DEPLOY_EVERY)
            for mirror in ("", MIRRORED)
            for r in FIG3_RATIOS
        ]
    if figure in ("fig4", "fig5"):
        counts = FIG4_FOOTBOTS if figure == "fig4" else FIG5_FOOTBOTS
        return [Point(_corridor(1.0), n, deploy_every=DEPLOY_EVERY) for n in counts]
    if figure == "beyond":
        return [
            Point(_corridor(1.5), n, way, DEPLOY_EVERY)
            for n in BEYOND_FOOTBOTS
            for way in ("learning", "weigh")
        ]
    raise ValueError(f"unknown figure {figure!r}")


def _corridor(ratio: float) -> str:
    return f"corridor-r{ratio:g}"


@functools.cache
def arena(name: str, over_walls: bool = False) -> Arena:
    """The arena a point names (``over_walls``: the cluttered one's old eye-bot placement)."""
    if name == "cluttered":
        return cluttered(over_walls)
    if name.startswith("corridor-r"):
        ratio = name.removeprefix("corridor-r").removesuffix(MIRRORED)
        return corridors(float(ratio), mirrored=name.endswith(MIRRORED))
    raise ValueError(f"unknown arena {name!r}")


def run_seed(master: int, run_index: int) -> int:
    """The seed of run ``run_index`` (the same at every point)."""
    return int(np.random.SeedSequence([master, run_index]).generate_state(1)[0])


def _one(job: tuple[EyebotSettings, Point, int]) -> Record:
    s, p, k = job
    a = arena(p.arena, s.over_walls)
    settings = Settings(
        footbots=p.footbots,
        duration=s.duration,
        deploy_every=p.deploy_every,
        shortest=p.eyebots == "shortest",
        weigh=p.eyebots == "weigh",
        period=s.period,
        reading=s.reading,
        window=min(1000.0, s.duration / 3),
        motion=Motion(head_on_right=s.head_on_right),
    )
    if settings.weigh:  # the reference trip: the shortest way through the eye-bots
        settings = replace(settings, weigh_reference=a.optimum / settings.motion.speed)
    rec = run(a, settings, run_seed(s.seed, k))
    rec.update(point=p.name, eyebots=p.eyebots, run=k, seed=s.seed, over_walls=s.over_walls)
    return rec


def run_points(
    s: EyebotSettings, pts: list[Point], label: str = ""
) -> tuple[list[Record], Made, float]:
    """Every run of ``pts`` (:func:`experiments._runner.run_points`; none made with
    ``saved_only``): all records, a tally of the runs made (their simulated foot-bot seconds
    and wall seconds), and the wall seconds spent making them."""
    made = Made(sim_s=lambda r: r["footbots"] * r["duration"], wall_s=lambda r: r["wall_s"])
    records, wall = _runner.run_points(
        s,
        pts,
        _one,
        made,
        label=label,
        status=lambda rec: f"{rec['point']} run {rec['run']}",
        make=not s.saved_only,
    )
    return records, made, wall
