"""Seeded foraging trials in-process, and the rows of the paper's tables they make up.

Time is the paper's (section 5.1): iterations until every resource location is exhausted, one
iteration being every agent acting once. The base is in the centre and every agent starts there.
Every trial's seed derives from the master seed: the environment of run k is the same for every
agent count (common random numbers), the agents' generator differs.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robots.foraging import AntAgent, CMarkingAgent
from sim_hw.grid import Grid, GridWorld, PheromoneField, place_resources, random_obstacles

from .._common import Progress, Summary, summary
from ._paper import PAPER_T1, PAPER_T2, PAPER_T3, SETUP1, SETUP2, SETUP3_AGENTS, Setup, setup3
from ._settings import TARGET_SE, ForagingSettings


def environment(setup: Setup, env: np.random.Generator) -> tuple[Grid, tuple[int, int]]:
    """A random obstacle field with the base in the centre, every free cell reachable from it.

    At 30 % obstacles the base is now and then walled into a pocket of a few cells (about 1 draw
    in 100); such a draw is discarded and the next one from the same generator taken, until the
    base's region holds at least half the free cells expected at that density.
    """
    base = (setup.size // 2, setup.size // 2)
    need = 0.5 * (1 - setup.density) * setup.size**2
    while True:
        grid = random_obstacles(setup.size, setup.size, setup.density, env, keep_free=(base,))
        if (~grid.obstacles).sum() >= max(need, setup.n_resources + 1):
            return grid, base


@dataclass
class Trial:
    """The outcome of one run."""

    iterations: int
    finished: bool
    agent_steps: int


def run_trial(
    setup: Setup, n_agents: int, kind: str, env_seed: Sequence[int], agent_seed: Sequence[int],
    max_iterations: int, until: str = "exhausted", literal: bool = False,
    forget_at_base: bool = False, colour_source: bool = True, trail_colours: str = "single",
    climb_any: bool = False,
) -> Trial:  # fmt: skip
    """One seeded foraging run; ``kind`` is "cmarking" or "ants". Agent i of a per-trail team
    takes ident i (its own trail colours)."""
    env = np.random.default_rng(np.random.SeedSequence(list(env_seed)))
    grid, base = environment(setup, env)
    res = place_resources(grid, setup.n_resources, setup.quantity, env, exclude=(base,))
    rngs = np.random.default_rng(np.random.SeedSequence(list(agent_seed))).spawn(n_agents)
    ants = kind == "ants"
    if ants:
        field_ = PheromoneField(~grid.obstacles)
        world = GridWorld(grid, base, res, n_agents, pheromone=field_)
        agents: list[Any] = [AntAgent(r, setup.q_max) for r in rngs]
    else:
        world = GridWorld(grid, base, res, n_agents)
        agents = [
            CMarkingAgent(r, setup.q_max, not literal, forget_at_base, colour_source,
                          trail_colours=trail_colours, climb_any=climb_any, ident=i,
                          team=n_agents)
            for i, r in enumerate(rngs)
        ]  # fmt: skip
    step = world.step

    def done() -> bool:
        return bool(world.all_delivered if until == "delivered" else world.exhausted)

    while not done() and world.iteration < max_iterations:
        step(agents, ants)
    return Trial(world.iteration, done(), world.iteration * n_agents)


@dataclass
class Row:
    """Measurements of one table row: the iterations of its finished runs.

    With ``draws`` > 1 each environment is run with that many agent seeds (common random
    numbers): ``values`` holds every finished run, ``env_means`` the mean of each environment's
    finished runs, and the standard error is over environments, the independent unit.
    """

    label: str
    values: list[int] = field(default_factory=list)
    unfinished: int = 0
    agent_steps: int = 0
    seconds: float = 0.0
    draws: int = 1
    env_means: list[float] = field(default_factory=list)
    #: by_draw[j]: the finished runs of agent seed j, one per environment.
    by_draw: list[list[int]] = field(default_factory=list)

    @property
    def stats(self) -> Summary:
        """Mean, sample standard deviation and standard error of the finished runs."""
        return summary(self.values, ddof=1)

    @property
    def n(self) -> int:
        """Finished runs."""
        return len(self.values)

    @property
    def mean(self) -> float:
        """Mean iterations of the finished runs (nan without any)."""
        return self.stats.mean

    @property
    def rel_se(self) -> float:
        """The standard error of the mean as a share of it: over runs, or over environments
        when each environment has several agent seeds."""
        return summary(self.env_means).rel_se if self.draws > 1 else self.stats.rel_se

    @property
    def envs(self) -> int:
        """Environments with at least one finished run."""
        return len(self.env_means) if self.draws > 1 else self.n


def measure(label: str, one: Callable[[int, int], Trial], s: ForagingSettings) -> Row:
    """Run ``one(run_index, draw)`` for ``s.runs`` environments and ``s.agent_seeds`` draws
    each, or until the SE is ≤ 5 % of the mean."""
    row = Row(label, draws=s.agent_seeds, by_draw=[[] for _ in range(s.agent_seeds)])
    fixed = s.runs is not None
    total = s.runs if s.runs is not None else s.max_runs
    bar = Progress(total, label, width=24, enabled=not s.quiet)
    t0 = time.perf_counter()
    k = 0
    while k < total:
        if not fixed and row.envs >= s.min_runs and row.rel_se <= TARGET_SE:
            break
        done: list[int] = []
        for j in range(s.agent_seeds):
            trial = one(k, j)
            row.agent_steps += trial.agent_steps
            if trial.finished:
                row.values.append(trial.iterations)
                row.by_draw[j].append(trial.iterations)
                done.append(trial.iterations)
            else:
                row.unfinished += 1
        if done:
            row.env_means.append(sum(done) / len(done))
        k += 1
        bar.update(k, _status(row, time.perf_counter() - t0))
    row.seconds = time.perf_counter() - t0
    bar.close(k, _status(row, row.seconds))
    return row


def _status(row: Row, seconds: float) -> str:
    st = row.stats
    se = f"{100 * row.rel_se:5.1f}%" if row.envs > 1 else "   -  "
    rate = row.agent_steps / max(seconds, 1e-9)
    return f"se {se}  mean {st.mean:8.1f}  {rate / 1e3:6.1f}k agent-steps/s"


def runner(
    s: ForagingSettings, setup: Setup, n: int, kind: str, table: int, variant: int
) -> Callable[[int, int], Trial]:
    """Run k, agent seed j, of a row. The environment seed is (seed, table, k) — the same for
    every row of a table (common random numbers) — and the agents' seed adds the row and the
    kind, and j when j > 0 (draw 0 is the seed of a single-draw run)."""
    code = 0 if kind == "cmarking" else 1

    def one(k: int, j: int = 0) -> Trial:
        env_seed = (s.seed, table, k)
        agent_seed = (s.seed, table, k, variant, code, *((j,) if j else ()))
        return run_trial(
            setup, n, kind, env_seed, agent_seed, s.max_iterations, s.until, s.literal,
            s.forget_at_base, not s.colour_on_move, s.trail_colours, s.climb_any,
        )  # fmt: skip

    return one


# -- the tables' rows ------------------------------------------------------------------------
def table1_rows(s: ForagingSettings) -> tuple[list[int], list[Row]]:
    """Table 1: Setup 1, c-marking, 5 to 160 agents (or ``s.agents``)."""
    counts = list(s.agents) or sorted(PAPER_T1)
    return counts, [
        measure(f"table1 {n} agents", runner(s, SETUP1, n, "cmarking", 1, n), s) for n in counts
    ]


def table2_rows(s: ForagingSettings) -> tuple[list[int], list[Row]]:
    """Table 2: Setup 2, c-marking, 1 to 8 agents (or ``s.agents``)."""
    counts = list(s.agents) or sorted(PAPER_T2)
    return counts, [
        measure(f"table2 {n} agents", runner(s, SETUP2, n, "cmarking", 2, n), s) for n in counts
    ]


def table3_rows(
    s: ForagingSettings, kinds: tuple[str, ...]
) -> tuple[list[int], dict[str, list[Row]]]:
    """Table 3 (c-marking) and Figure 9 (with ants): Setup 3 at each side, 50 agents."""
    sizes = list(s.sizes) or sorted(PAPER_T3)
    rows = {
        kind: [
            measure(f"{kind} {z}x{z}", runner(s, setup3(z), SETUP3_AGENTS, kind, 3, z), s)
            for z in sizes
        ]
        for kind in kinds
    }
    return sizes, rows
