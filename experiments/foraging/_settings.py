"""What a foraging experiment runs and reports: one frozen record, made from the command line."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

#: Adaptive mode: a row runs until its standard error is at most this share of its mean.
TARGET_SE = 0.05
TABLES = ("1", "2", "3", "ants", "model", "all")


@dataclass(frozen=True)
class ForagingSettings:
    """The tables to run (every trial's seed derives from ``seed``) and what to print.

    ``runs`` fixes the runs per row; None: adaptive, until the standard error is at most
    :data:`TARGET_SE` of the mean, with ``min_runs`` to ``max_runs`` runs. ``agents`` and
    ``sizes`` replace the paper's agent counts (tables 1, 2) and sides (table 3, ants). The
    c-marking variants are ``literal``, ``forget_at_base``, ``colour_on_move``, ``climb_any``
    and ``trail_colours`` ("single" or "per-trail"). ``agent_seeds`` runs every environment with
    that many agent seeds (the standard error is then over environments).
    """

    seed: int = 2007
    table: str = "all"
    runs: int | None = None
    min_runs: int = 30
    max_runs: int = 1000
    agents: tuple[int, ...] = ()
    sizes: tuple[int, ...] = ()
    max_iterations: int = 200_000
    until: str = "exhausted"
    literal: bool = False
    forget_at_base: bool = False
    colour_on_move: bool = False
    trail_colours: str = "single"
    climb_any: bool = False
    agent_seeds: int = 1
    #: ``model``: our stored times to fit beside the paper's, as (label, files) pairs.
    fit: tuple[tuple[str, tuple[str, ...]], ...] = ()
    out: Path | None = Path("out")
    format: str = "png"
    quiet: bool = False
    json: bool = False

    @property
    def reading(self) -> dict[str, object]:
        """The settings beyond the first ones a report names, where they are not the default
        (so that a default run prints and dumps what it always did)."""
        extra: dict[str, object] = {}
        if self.trail_colours != "single":
            extra["trail_colours"] = self.trail_colours
        if self.climb_any:
            extra["climb_any"] = True
        if self.agent_seeds != 1:
            extra["agent_seeds"] = self.agent_seeds
        return extra

    @property
    def tables(self) -> list[str]:
        """The tables to run, in order."""
        return ["1", "2", "ants", "3"] if self.table == "all" else [self.table]
