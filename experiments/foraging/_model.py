"""How consistent are the paper's Tables 1-3 with one another? A two-term model of foraging time.

Foraging ends when the last source is exhausted, so its time is roughly what it takes to find
every source plus what it takes to empty them. Measured on our own environments with our own
code, for each row of a table:

* ``D``: iterations until a team of that many agents exploring as in Simonin et al.,
  Algorithm 2 (EXPLORATION & APF CONSTRUCTION, no trails) has detected every source (stood on
  it or beside it, as a c-marking agent detects one, Algorithm 4);
* ``TB``: the transport lower bound, Σ over sources of (2·trips − 1)·path / agents, with
  trips = ⌈quantity / q_max⌉ and path the shortest path from the base (Algorithm 1's
  wavefront): every unit carried home along a shortest path, the last trip ending at the
  source, the work shared evenly.

Then ``T = a·D + b·TB`` is fitted (least squares on relative error, a, b ≥ 0) to each table's times
(the paper's, or ours with some reading). ``b`` is the overhead per trip over a shortest path:
how many times the bare transport the team spends on it, trails included. Geometry and agent
counts are in D and TB; what is left in ``b`` is the algorithm, which should not differ between
tables run with the same algorithm on similar floors (Setups 2 and 3 are both 5 % obstacles).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from robots.foraging import MarkingAgent
from sim_hw.grid import GridWorld, place_resources

from ._paper import PAPER_T1, PAPER_T2, PAPER_T3, SETUP1, SETUP2, SETUP3_AGENTS, Setup, setup3
from ._settings import ForagingSettings
from ._trial import Row, Trial, environment, measure

#: Agent seeds of the explorers add this code after the row (c-marking 0, ants 1).
EXPLORERS = 2


def discovery(
    setup: Setup, n_agents: int, env_seed: Sequence[int], agent_seed: Sequence[int],
    max_iterations: int,
) -> tuple[Trial, float]:  # fmt: skip
    """One environment: (the exploring team's discovery time D as a :class:`Trial`, TB).

    The environment is the one :func:`~experiments.foraging.run_trial` builds from
    ``env_seed``, so that D and TB pair with the foraging runs of the same seed.
    """
    env = np.random.default_rng(np.random.SeedSequence(list(env_seed)))
    grid, base = environment(setup, env)
    res = place_resources(grid, setup.n_resources, setup.quantity, env, exclude=(base,))
    dist = grid.distances(base)
    trips = math.ceil(setup.quantity / setup.q_max)
    tb = sum((2 * trips - 1) * int(dist[c]) for c in res) / n_agents
    world = GridWorld(grid, base, res, n_agents)
    # detects[i]: the sources seen from cell i (on it or in a 4-neighbour)
    detects: dict[int, list[int]] = {}
    for s, cell in enumerate(res):
        for c in [cell, *grid.neighbours(cell)]:
            detects.setdefault(grid.index(c), []).append(s)
    unseen = set(range(len(res)))
    rngs = np.random.default_rng(np.random.SeedSequence(list(agent_seed))).spawn(n_agents)
    agents = [MarkingAgent(r) for r in rngs]

    def look() -> None:
        for p in world.positions:
            for s in detects.get(p, ()):
                unseen.discard(s)

    look()
    while unseen and world.iteration < max_iterations:
        world.step(agents)
        look()
    return Trial(world.iteration, not unseen, world.iteration * n_agents), tb


@dataclass
class ModelRow:
    """D and TB of one table row, over the environments measured."""

    key: int
    d: Row
    tb: list[float]

    @property
    def tb_mean(self) -> float:
        """Mean transport bound over the environments."""
        return float(np.mean(self.tb))


def model_rows(s: ForagingSettings, table: int) -> list[ModelRow]:
    """D and TB for each row of Table ``table`` (1, 2 or 3), on that table's environments."""
    if table == 3:
        keys = list(s.sizes) or sorted(PAPER_T3)
        setups = {z: (setup3(z), SETUP3_AGENTS) for z in keys}
    else:
        paper = PAPER_T1 if table == 1 else PAPER_T2
        keys = list(s.agents) or sorted(paper)
        setups = {n: (SETUP1 if table == 1 else SETUP2, n) for n in keys}
    return [model_row(s, table, key, *setups[key]) for key in keys]


def model_row(s: ForagingSettings, table: int, key: int, setup: Setup, n: int) -> ModelRow:
    """D and TB of one row: environments (seed, table, k) as the table's foraging runs."""
    tb: dict[int, float] = {}

    def one(k: int, j: int) -> Trial:
        seed = (s.seed, table, k, key, EXPLORERS, *((j,) if j else ()))
        trial, tb[k] = discovery(setup, n, (s.seed, table, k), seed, s.max_iterations)
        return trial

    d = measure(f"model t{table} {key}", one, s)
    return ModelRow(key, d, list(tb.values()))


@dataclass(frozen=True)
class Fit:
    """``T ≈ a·D + b·TB`` fitted to one table's times; ``rms`` the relative error."""

    a: float
    b: float
    rms: float


def fit(rows: Sequence[ModelRow], times: Mapping[int, float]) -> Fit | None:
    """Least squares on relative error over the rows with a time; None with fewer than 2."""
    use = [r for r in rows if r.key in times and r.d.n and not math.isnan(times[r.key])]
    return fit_points([(r.d.mean, r.tb_mean, times[r.key]) for r in use])


def fit_points(points: Sequence[tuple[float, float, float]]) -> Fit | None:
    """:func:`fit` over (D, TB, T) triples, from one table or pooled over several.

    Non-negative least squares: a time is not shortened by a longer search or a longer
    transport, and where D and TB scale alike (Setup 2: both ∝ 1/agents) an unconstrained fit
    trades a negative a for a larger b. With two unknowns, the constrained optimum is the
    unconstrained one if both are non-negative, else the better of the one-term fits.
    """
    if len(points) < 2:
        return None
    t = np.array([p[2] for p in points])
    x = np.array([[p[0], p[1]] for p in points]) / t[:, None]
    ones = np.ones(len(points))
    coef, *_ = np.linalg.lstsq(x, ones, rcond=None)
    if (coef < 0).any():
        one_term = []
        for col in (0, 1):
            c = np.zeros(2)
            c[col] = max(0.0, float(x[:, col] @ ones / (x[:, col] @ x[:, col])))
            one_term.append(c)
        coef = min(one_term, key=lambda c: float(np.sum((x @ c - 1) ** 2)))
    rms = float(np.sqrt(np.mean((x @ coef - 1) ** 2)))
    return Fit(float(coef[0]), float(coef[1]), rms)


def pooled(
    tables: Mapping[int, Sequence[ModelRow]], times: Mapping[int, Mapping[int, float]]
) -> str:
    """One (a, b) for the rows of every table at once: how far one algorithm explains them."""
    points = [
        (r.d.mean, r.tb_mean, times[t][r.key])
        for t, rows in tables.items()
        for r in rows
        if r.key in times.get(t, {}) and r.d.n
    ]
    f = fit_points(points)
    if f is None:
        return "  pooled: too few rows"
    return (f"  pooled over Tables {', '.join(map(str, sorted(tables)))}: a {f.a:6.3f}  "
            f"b {f.b:6.2f}  rms {100 * f.rms:5.1f}%")  # fmt: skip


def paper_times(table: int) -> dict[int, float]:
    """The paper's mean iterations of Table ``table``, by row."""
    if table == 3:
        return dict(PAPER_T3)
    return {n: float(v[0]) for n, v in (PAPER_T1 if table == 1 else PAPER_T2).items()}


def report(
    table: int, rows: Sequence[ModelRow], ours: Mapping[str, Mapping[int, float]], seed: int
) -> tuple[str, dict[str, object]]:
    """The rows' D and TB, and the fits to the paper's table and to each of ``ours``."""
    key = "size" if table == 3 else "agents"
    lines = [
        f"\nModel T = a*D + b*TB, Table {table}; D explored on our environments, TB from their"
        f" shortest paths; seed {seed}",
        f"{key:>6} | {'D':>8} {'se%':>5} | {'TB':>8} | {'paper T':>8}"
        + "".join(f" | {label[:12]:>12}" for label in ours),
    ]
    paper = paper_times(table)
    for r in rows:
        theirs = "".join(f" | {o.get(r.key, math.nan):12.1f}" for o in ours.values())
        lines.append(
            f"{r.key:>6} | {r.d.mean:8.1f} {100 * r.d.rel_se:5.1f} | {r.tb_mean:8.1f} | "
            f"{paper.get(r.key, math.nan):8.1f}{theirs}"
        )
    fits: dict[str, object] = {}
    for label, times in {"paper": paper, **ours}.items():
        f = fit(rows, times)
        if f is None:
            continue
        lines.append(f"  fit to {label:<24} a {f.a:6.3f}  b {f.b:6.2f}  rms {100 * f.rms:5.1f}%")
        fits[label] = {"a": round(f.a, 3), "b": round(f.b, 2), "rms": round(f.rms, 4)}
    figures = {
        "D": {str(r.key): round(r.d.mean, 1) for r in rows},
        "TB": {str(r.key): round(r.tb_mean, 1) for r in rows},
        "fits": fits,
    }
    return "\n".join(lines), {f"model{table}": figures}


def load_times(files: Sequence[str], table: int) -> dict[int, float]:
    """Our times of Table ``table`` from stored runs: the last line (the runner's ``--json``)
    of each file, rows merged over the files (one file per row, or one per table)."""
    times: dict[int, float] = {}
    for name in files:
        with open(name, encoding="utf-8") as f:
            last = f.read().strip().splitlines()[-1]
        for k, v in json.loads(last).get(f"table{table}", {}).items():
            if v is not None:
                times[int(k)] = float(v)
    return times
