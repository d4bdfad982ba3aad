"""`mover experiment foraging`: Simonin et al.'s foraging tables, re-measured in-process.

Runs many seeded trials of c-marking agents (Algorithm 4) and of the ant-model baseline on the
grid world, and prints the paper's Tables 1–3 and the Figure 9 comparison beside ours:

* Table 1 — Setup 1: 40×40, 30 % obstacles, 20 resources × 1000 units, q_max 100, 5…160 agents;
* Table 2 — Setup 2: 20×20, 5 %, 2 resources × 1000; 1…8 agents; projected V_ref/n vs measured;
* Table 3 — Setup 3: 12×12…200×200, 5 %, 20 resources × 2000, 50 agents; ratio R;
* Figure 9 ("ants") — c-marking vs ants in Setup 3.

Time is the paper's (section 5.1): iterations until every resource location is exhausted, one
iteration being every agent acting once. The base is in the centre and every agent starts there.
Every trial's seed derives from ``--seed``: the environment of run k is the same for every agent
count (common random numbers), the agents' generator differs. By default each row runs until the
standard error is at most 5 % of its mean (at least ``--min-runs`` runs, at most ``--max-runs``);
``--runs N`` fixes the count instead.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from robots.foraging import AntAgent, CMarkingAgent
from sim_hw.grid import Grid, GridWorld, PheromoneField, place_resources, random_obstacles

# The paper's figures: Table 1 (mean, std), Table 2 (measured, projected), Table 3 (iterations).
PAPER_T1 = {5: (19200, 10071), 10: (8697, 4282), 20: (4114, 1890), 40: (2263, 1134),
            80: (1070, 448), 160: (574, 420)}  # fmt: skip
PAPER_T2 = {1: (1790.4, 1790.4), 2: (871.5, 895.2), 3: (582.9, 596.8), 4: (438.7, 447.6),
            5: (356.1, 358.1), 6: (302.0, 298.4), 7: (266.5, 255.8), 8: (236.2, 223.8)}  # fmt: skip
PAPER_T3 = {12: 155.5, 25: 345.0, 50: 805.0, 100: 2290.0, 200: 7844.0}
#: Section 5.5: "the difference ... decreases (from 73% to 52% to 37%)" as the size grows.
PAPER_FIG9_GAPS = (73, 52, 37)
TARGET_SE = 0.05


@dataclass(frozen=True)
class Setup:
    """One of the paper's setups (sections 4.5, 5.3, 5.4)."""

    size: int
    density: float
    n_resources: int
    quantity: int
    q_max: int = 100


SETUP1 = Setup(40, 0.30, 20, 1000)
SETUP2 = Setup(20, 0.05, 2, 1000)


def setup3(size: int) -> Setup:
    """Setup 3 at one environment size."""
    return Setup(size, 0.05, 20, 2000)


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
    forget_at_base: bool = False, colour_source: bool = True,
) -> Trial:  # fmt: skip
    """One seeded foraging run; ``kind`` is "cmarking" or "ants"."""
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
            CMarkingAgent(r, setup.q_max, not literal, forget_at_base, colour_source) for r in rngs
        ]
    step = world.step

    def done() -> bool:
        return bool(world.all_delivered if until == "delivered" else world.exhausted)

    while not done() and world.iteration < max_iterations:
        step(agents, ants)
    return Trial(world.iteration, done(), world.iteration * n_agents)


@dataclass
class Row:
    """Measurements of one table row."""

    label: str
    values: list[int] = field(default_factory=list)
    unfinished: int = 0
    agent_steps: int = 0
    seconds: float = 0.0

    @property
    def n(self) -> int:
        return len(self.values)

    @property
    def mean(self) -> float:
        return float(np.mean(self.values)) if self.values else math.nan

    @property
    def std(self) -> float:
        return float(np.std(self.values, ddof=1)) if self.n > 1 else math.nan

    @property
    def rel_se(self) -> float:
        """Standard error as a fraction of the mean."""
        return self.std / math.sqrt(self.n) / self.mean if self.n > 1 else math.inf


class Progress:
    """A plain-text progress line on stderr."""

    def __init__(self, label: str, total: int, enabled: bool = True) -> None:
        self.label, self.total, self.enabled = label, total, enabled
        self.t0 = time.perf_counter()
        self.last = 0.0

    def update(self, done: int, row: Row, force: bool = False) -> None:
        now = time.perf_counter()
        if not self.enabled or (not force and now - self.last < 0.5):
            return
        self.last = now
        width = 24
        filled = int(width * min(done, self.total) / max(self.total, 1))
        rate = row.agent_steps / max(now - self.t0, 1e-9)
        se = f"{100 * row.rel_se:5.1f}%" if row.n > 1 else "   -  "
        sys.stderr.write(
            f"\r{self.label:<22} [{'#' * filled}{'.' * (width - filled)}] {done:>4}/{self.total:<4}"
            f" se {se}  mean {row.mean:8.1f}  {rate / 1e3:6.1f}k agent-steps/s"
        )
        sys.stderr.flush()

    def close(self, done: int, row: Row) -> None:
        if self.enabled:
            self.update(done, row, force=True)
            sys.stderr.write("\n")


def measure(label: str, one: Callable[[int], Trial], args: argparse.Namespace) -> Row:
    """Run ``one(run_index)`` for ``--runs`` runs, or until the SE is ≤ 5 % of the mean."""
    row = Row(label)
    fixed = args.runs is not None
    total = args.runs if fixed else args.max_runs
    bar = Progress(label, total, not args.quiet)
    t0 = time.perf_counter()
    k = 0
    while k < total:
        if not fixed and row.n >= args.min_runs and row.rel_se <= TARGET_SE:
            break
        trial = one(k)
        k += 1
        row.agent_steps += trial.agent_steps
        if trial.finished:
            row.values.append(trial.iterations)
        else:
            row.unfinished += 1
        bar.update(k, row)
    row.seconds = time.perf_counter() - t0
    bar.close(k, row)
    return row


def _runner(
    args: argparse.Namespace, setup: Setup, n: int, kind: str, table: int, variant: int
) -> Callable[[int], Trial]:
    """Run k of a row. The environment seed is (seed, table, k) — the same for every row of a
    table (common random numbers) — and the agents' seed adds the row and the kind."""
    code = 0 if kind == "cmarking" else 1

    def one(k: int) -> Trial:
        env_seed = (args.seed, table, k)
        agent_seed = (args.seed, table, k, variant, code)
        return run_trial(
            setup, n, kind, env_seed, agent_seed, args.max_iterations, args.until, args.literal,
            args.forget_at_base, not args.colour_on_move,
        )  # fmt: skip

    return one


def _cell(row: Row) -> str:
    return f"{row.mean:9.1f} ±{row.std:7.1f}" if row.n else "      n/a         "


def _runs(row: Row) -> str:
    miss = f" +{row.unfinished} unfinished" if row.unfinished else ""
    return f"{row.n:5d} runs, se {100 * row.rel_se:4.1f}%{miss}"


def table1(args: argparse.Namespace, out: dict[str, Any]) -> list[Row]:
    """Table 1: Setup 1, 5 to 160 agents."""
    rows = []
    counts = args.agents or sorted(PAPER_T1)
    for n in counts:
        rows.append(measure(f"table1 {n} agents", _runner(args, SETUP1, n, "cmarking", 1, n), args))
    print(f"\nTable 1 — Setup 1 (40x40, 30 % obstacles, 20 x 1000, q_max 100); seed {args.seed}")
    print(f"{'agents':>6} | {'paper mean ± std':>18} | {'ours mean ± std':>18} | {'ours/paper':>10}"
          " | runs")  # fmt: skip
    for n, row in zip(counts, rows, strict=True):
        pm, ps = PAPER_T1.get(n, (math.nan, math.nan))
        print(
            f"{n:>6} | {pm:9.1f} ±{ps:7.1f} | {_cell(row)} | {row.mean / pm:10.2f} | {_runs(row)}"
        )
    out["table1"] = {str(n): round(r.mean, 1) for n, r in zip(counts, rows, strict=True)}
    out["table1_std"] = {str(n): round(r.std, 1) for n, r in zip(counts, rows, strict=True)}
    return rows


def table2(args: argparse.Namespace, out: dict[str, Any]) -> list[Row]:
    """Table 2: Setup 2, 1 to 8 agents, projected V_ref / n vs measured."""
    counts = args.agents or sorted(PAPER_T2)
    rows = [
        measure(f"table2 {n} agents", _runner(args, SETUP2, n, "cmarking", 2, n), args)
        for n in counts
    ]
    vref = rows[0].mean * counts[0]
    print(f"\nTable 2 — Setup 2 (20x20, 5 %, 2 x 1000); projected = V_ref/n; seed {args.seed}")
    print(
        f"{'agents':>6} | {'paper exp':>9} {'proj':>7} {'proj-exp':>8} | "
        f"{'ours exp':>9} {'proj':>8} {'proj-exp':>8} {'(%)':>6} | runs"
    )
    for n, row in zip(counts, rows, strict=True):
        pe, pp = PAPER_T2.get(n, (math.nan, math.nan))
        proj = vref / n
        print(
            f"{n:>6} | {pe:9.1f} {pp:7.1f} {pp - pe:8.1f} | {row.mean:9.1f} {proj:8.1f} "
            f"{proj - row.mean:8.1f} {100 * (proj - row.mean) / proj:6.1f} | {_runs(row)}"
        )
    out["table2"] = {str(n): round(r.mean, 1) for n, r in zip(counts, rows, strict=True)}
    return rows


def table3(
    args: argparse.Namespace, out: dict[str, Any], kinds: tuple[str, ...]
) -> dict[str, list[Row]]:
    """Table 3 (c-marking) and Figure 9 (with ants): Setup 3 at each size, 50 agents."""
    sizes = args.sizes or sorted(PAPER_T3)
    rows: dict[str, list[Row]] = {}
    for kind in kinds:
        rows[kind] = [
            measure(f"{kind} {s}x{s}", _runner(args, setup3(s), 50, kind, 3, s), args)
            for s in sizes
        ]
    cm = rows["cmarking"]
    print(
        f"\nTable 3 — Setup 3 (5 %, 20 x 2000, 50 agents); R = ratio to the previous size;"
        f" seed {args.seed}"
    )
    print(f"{'size':>8} | {'paper':>7} {'R':>5} | {'ours mean ± std':>18} {'R':>5} | runs")
    prev_p = prev_o = None
    for s, row in zip(sizes, cm, strict=True):
        p = PAPER_T3.get(s, math.nan)
        rp = f"{p / prev_p:5.2f}" if prev_p else "     "
        ro = f"{row.mean / prev_o:5.2f}" if prev_o else "     "
        print(f"{f'{s}x{s}':>8} | {p:7.1f} {rp} | {_cell(row)} {ro} | {_runs(row)}")
        prev_p, prev_o = p, row.mean
    out["table3"] = {str(s): round(r.mean, 1) for s, r in zip(sizes, cm, strict=True)}
    if "ants" in rows:
        print(
            f"\nFigure 9 — c-marking vs ants, Setup 3; gap = (ants - c-marking) / ants; paper's "
            f"gaps shrink {'% → '.join(map(str, PAPER_FIG9_GAPS))}% with size; seed {args.seed}"
        )
        print(f"{'size':>8} | {'c-marking':>18} | {'ants':>18} | {'gap':>5} | ants runs")
        for s, c, a in zip(sizes, cm, rows["ants"], strict=True):
            gap = 100 * (a.mean - c.mean) / a.mean if a.n else math.nan
            print(f"{f'{s}x{s}':>8} | {_cell(c)} | {_cell(a)} | {gap:4.0f}% | {_runs(a)}")
        out["fig9"] = {
            "cmarking": out["table3"],
            "ants": {str(s): round(r.mean, 1) for s, r in zip(sizes, rows["ants"], strict=True)},
            "ants_unfinished": {str(s): r.unfinished for s, r in zip(sizes, rows["ants"],
                                                                     strict=True)},
        }  # fmt: skip
    return rows


def plot(out_dir: Path, name: str, xs: list[int], series: dict[str, list[float]],
         xlabel: str, title: str) -> Path:  # fmt: skip
    """A log-log PNG of iteration curves (matplotlib, Agg backend)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for label, ys in series.items():
        ax.plot(xs, ys, marker="o", label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("iterations")
    ax.set_title(title)
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{name}.png"
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def run(args: argparse.Namespace) -> int:
    """Run the selected tables, print them beside the paper's, write plots, maybe JSON."""
    out: dict[str, Any] = {"seed": args.seed, "runs": args.runs or "auto", "until": args.until,
                 "literal": args.literal, "forget_at_base": args.forget_at_base,
                 "colour_on_move": args.colour_on_move}  # fmt: skip
    out_dir = Path(args.out)
    tables = ["1", "2", "ants", "3"] if args.table == "all" else [args.table]
    t0 = time.perf_counter()
    steps = 0
    print(
        f"foraging experiment: seed {args.seed}, runs "
        f"{args.runs or f'auto (SE <= 5 % of the mean, {args.min_runs}..{args.max_runs})'}"
    )
    plots = []
    for t in tables:
        if t == "1":
            rows = table1(args, out)
            xs = args.agents or sorted(PAPER_T1)
            plots.append(plot(out_dir, "table1", xs, {
                "paper": [PAPER_T1.get(n, (math.nan,))[0] for n in xs],
                "ours": [r.mean for r in rows]}, "agents", "Table 1 (Setup 1)"))  # fmt: skip
        elif t == "2":
            rows = table2(args, out)
            xs = args.agents or sorted(PAPER_T2)
            vref = rows[0].mean * xs[0]
            plots.append(plot(out_dir, "table2", xs, {
                "paper measured": [PAPER_T2.get(n, (math.nan,))[0] for n in xs],
                "ours measured": [r.mean for r in rows],
                "ours projected V_ref/n": [vref / n for n in xs]},
                "agents", "Table 2 (Setup 2)"))  # fmt: skip
        else:
            kinds = ("cmarking", "ants") if t == "ants" else ("cmarking",)
            got = table3(args, out, kinds)
            rows = [r for rs in got.values() for r in rs]
            xs = [s * s for s in (args.sizes or sorted(PAPER_T3))]
            series = {"paper c-marking": [PAPER_T3.get(round(math.sqrt(x)), math.nan)
                                          for x in xs]}  # fmt: skip
            series.update({f"ours {k}": [r.mean for r in v] for k, v in got.items()})
            plots.append(plot(out_dir, "fig9" if t == "ants" else "table3", xs, series,
                              "cells", "Setup 3, 50 agents"))  # fmt: skip
        steps += sum(r.agent_steps for r in rows)
        sec = sum(r.seconds for r in rows)
        print(
            f"speed: {sum(r.agent_steps for r in rows) / max(sec, 1e-9):,.0f} agent-steps/s"
            f" over {sec:.1f} s"
        )
    elapsed = time.perf_counter() - t0
    print(
        f"\ntotal: {steps:,} agent-steps in {elapsed:.1f} s = {steps / elapsed:,.0f} "
        f"agent-steps/s; plots: {', '.join(map(str, plots))}"
    )
    if args.json:
        print(json.dumps(_no_nan(out), allow_nan=False))
    return 0


def _no_nan(value: object) -> object:
    """The same structure with NaN (a row without a finished run) as null: strict JSON."""
    if isinstance(value, dict):
        return {k: _no_nan(v) for k, v in value.items()}
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def _int_list(text: str) -> list[int]:
    return [int(x) for x in text.split(",") if x]


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``foraging`` experiment to ``mover experiment``."""
    p = sub.add_parser(
        "foraging",
        help="Simonin et al. c-marking foraging tables 1-3, Fig. 9",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--table",
        choices=["1", "2", "3", "ants", "all"],
        default="all",
        help="which table (ants = Figure 9, c-marking vs ants); default all",
    )
    p.add_argument(
        "--runs",
        type=int,
        default=None,
        help="runs per row; default: until the SE is <= 5 %% of the mean",
    )
    p.add_argument("--min-runs", type=int, default=30, help="adaptive mode: at least (30)")
    p.add_argument("--max-runs", type=int, default=1000, help="adaptive mode: at most (1000)")
    p.add_argument("--seed", type=int, default=2007, help="master seed (2007)")
    p.add_argument(
        "--agents",
        type=_int_list,
        default=None,
        help="comma-separated agent counts for tables 1/2 (default: the paper's)",
    )
    p.add_argument(
        "--sizes",
        type=_int_list,
        default=None,
        help="comma-separated sides for table 3 / ants (default 12,25,50,100,200)",
    )
    p.add_argument(
        "--max-iterations",
        type=int,
        default=200_000,
        help="a run still going after this is counted unfinished (200000)",
    )
    p.add_argument(
        "--until",
        choices=["exhausted", "delivered"],
        default="exhausted",
        help="end of a run: resources exhausted (paper, 5.1) or also delivered",
    )
    p.add_argument(
        "--literal",
        action="store_true",
        help="c-marking exactly as Algorithm 4 (no removal of dead-end trails)",
    )
    p.add_argument(
        "--forget-at-base",
        action="store_true",
        help="c-marking variant: climb straight back the trail just come down",
    )
    p.add_argument(
        "--colour-on-move",
        action="store_true",
        help="c-marking variant: colour only cells moved into, not the source cell",
    )
    p.add_argument("--json", action="store_true", help="end with one JSON line of every mean")
    p.add_argument("--out", default="out", help="directory for the PNG plots (out/)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
