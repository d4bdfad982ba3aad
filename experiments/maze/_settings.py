"""What a maze experiment runs and reports: one frozen record, made from the command line."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from robots.explore import EXCHANGES
from sim_hw.grid import Maze

from .._saved import Executor


@dataclass(frozen=True)
class MazeSettings:
    """The grid of trials (every trial's seed derives from ``seed``) and what to print.

    ``maze``: run on this maze (read from ``maze_path``) instead of generated ones; ``out``:
    the directory for the figures (None: none); ``load``: tabulate these saved runs instead of
    running; ``json``: end with a JSON line of every run; ``save``: the per-point JSON-lines
    directory read back and added to (None: keep nothing); ``workers`` and ``executor``: where
    the runs are made (:func:`experiments._saved.run_pool`).
    """

    seed: int
    runs: int
    hedac_runs: int
    methods: tuple[str, ...]
    agents: tuple[int, ...]
    size: int
    p: tuple[float, ...]
    exchanges: int = EXCHANGES
    partition: str = "balanced"  # CU-LVP's regions (robots.explore.PARTITIONS)
    news: str = "on"  # how CU-LVP's agents pass on each other's news (robots.explore.NEWS)
    maze: Maze | None = None
    maze_path: Path | None = None
    out: Path | None = None
    format: str = "png"
    load: tuple[Path, ...] = ()
    json: bool = False
    save: Path | None = None
    workers: int = 1
    executor: Executor = field(default_factory=Executor)

    def runs_for(self, method: str) -> int:
        """Runs of ``method`` per cell (HEDAC, the slow method, may have fewer)."""
        return min(self.runs, self.hedac_runs) if method == "hedac" else self.runs
