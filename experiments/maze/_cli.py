"""`mover experiment maze`: CU-LVP and its baselines on seeded mazes, in-process.

Linardakis et al., sections IV-V. Each trial builds a maze (section IV-A), puts N agents on its
first N start cells, and runs rounds until the union of the agents' maps knows every inner cell
the agents can see (an observer measures it; the agents never see it). Per round every agent
senses, broadcasts what changed (msgpack, delivered to the agents within range and decoded
from the bytes), hears, relays what it heard to the same agents (``--exchanges``), decides,
and moves, in agent order (a move into an occupied cell fails). Metrics (section IV-C):
rounds, exploration cost (4-connected moves made), efficiency M / cost, map quality
(M - errors) / P, communication (bytes actually sent, relays included, beside the paper's
equation (8)), and computation time per agent step (equation (4) uses its mean times rounds).
"""

from __future__ import annotations

import argparse
import json
import math
import secrets
import sys
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

from robots.explore import EXCHANGES, METHODS, ExplorerAgent, make_team
from sim_hw.grid import (
    Maze,
    MazeFileError,
    MazeWorld,
    generate_maze,
    load_maze,
    observable,
)

AGENT_COUNTS = (1, 2, 4, 6, 8, 10, 15, 20)
PROBABILITIES = (0.85, 0.15)
#: Metric key, label, whether larger is better (composite index, section V-B).
METRICS = (
    ("time_s", "exploration time (s, eq. 4)", False),
    ("rounds", "exploration rounds", False),
    ("cost", "exploration cost (cells moved, eq. 5)", False),
    ("efficiency", "exploration efficiency (eq. 6)", True),
    ("quality", "map quality (eq. 7)", True),
    ("comm_kB", "communication, msgpack bytes sent (kB)", False),
)
EXTRA = (
    ("comm_paper_kB", "communication, paper eq. 8 (kB)"),
    ("step_ms", "computation per agent step (ms)"),
)


def run_trial(
    maze: Maze,
    n_agents: int,
    method: str,
    seed: np.random.SeedSequence,
    max_rounds: int | None = None,
    exchanges: int = EXCHANGES,
) -> dict[str, Any]:
    """One seeded exploration run; returns its metrics (section IV-C). ``exchanges`` is the
    number of map exchanges per round (:data:`robots.explore.EXCHANGES`; 1: the paper's)."""
    world = MazeWorld(maze, n_agents)
    team = make_team(method, maze.shape, list(world.positions), seed)
    target = observable(maze.grid, list(world.positions))
    n_target = int(target.sum())
    known = np.zeros(maze.shape, dtype=bool)
    covered = 0
    rows, cols = maze.shape
    cap = max_rounds if max_rounds is not None else 5 * rows * cols  # a stuck team is reported
    rounds = cost = sent = heard_bytes = paper_bits = 0
    busy = 0.0

    def exchange(
        message: Callable[[ExplorerAgent], dict[str, Any]], alone_too: bool
    ) -> list[list[dict[str, Any]]]:
        """Every agent's message, packed with msgpack and delivered decoded to the agents in
        its range; an agent with nobody in range sends it only if ``alone_too``."""
        nonlocal sent, heard_bytes, busy
        inbox: list[list[dict[str, Any]]] = [[] for _ in team]
        for i, agent in enumerate(team):
            hearers = world.neighbours(i)
            if not hearers and not alone_too:
                continue
            t0 = time.perf_counter()
            packed = msgpack.packb(message(agent))
            busy += time.perf_counter() - t0
            sent += len(packed)
            if hearers:
                heard_bytes += len(packed)
                msg = msgpack.unpackb(packed)
                for j in hearers:
                    inbox[j].append(msg)
        return inbox

    while True:
        for i, agent in enumerate(team):
            seen = world.sense(i)
            t0 = time.perf_counter()
            agent.observe(seen_cells=seen, position=world.positions[i])
            busy += time.perf_counter() - t0
            for r, c, _ in seen:
                if target[r, c] and not known[r, c]:
                    known[r, c] = True
                    covered += 1
        if covered >= n_target or rounds >= cap:
            break
        inbox = exchange(lambda agent: agent.outgoing_message(), alone_too=True)
        pairs = sum(j > i for i in range(len(team)) for j in world.neighbours(i))
        paper_bits += pairs * 4 * rows * cols  # eq. (8) per communicating pair
        for i, agent in enumerate(team):
            t0 = time.perf_counter()
            agent.observe(heard_messages=inbox[i])
            busy += time.perf_counter() - t0
        for _ in range(exchanges - 1):  # relays, among the agents that heard each other
            relays = exchange(lambda agent: agent.relay_message(), alone_too=False)
            for i, agent in enumerate(team):
                if relays[i]:
                    t0 = time.perf_counter()
                    agent.hear_relay(relays[i])
                    busy += time.perf_counter() - t0
        for i, agent in enumerate(team):
            t0 = time.perf_counter()
            move = agent.decide()
            busy += time.perf_counter() - t0
            cost += world.move(i, move)
        rounds += 1
    return _metrics(
        maze, team, rounds, cost, sent, heard_bytes, paper_bits, busy, covered >= n_target, n_target
    )


def _metrics(
    maze: Maze,
    team: list[Any],
    rounds: int,
    cost: int,
    sent: int,
    heard: int,
    paper_bits: int,
    busy: float,
    complete: bool,
    n_target: int,
) -> dict[str, Any]:
    union = np.full(maze.shape, -1, dtype=np.int8)
    for agent in team:
        unknown = union == -1
        union[unknown] = agent.known[unknown]
    inner = (slice(1, -1), slice(1, -1))
    u, g = union[inner], maze.grid[inner]
    explored = int(np.count_nonzero(u != -1))
    errors = int(np.count_nonzero((u != -1) & (u != g)))
    steps = max(1, (rounds + 1) * len(team))
    step = busy / steps
    return {
        "rounds": rounds,
        "cost": cost,
        "efficiency": explored / max(cost, 1),
        "quality": (explored - errors) / u.size,
        "comm_kB": heard / 1000,
        "comm_sent_kB": sent / 1000,
        "comm_paper_kB": paper_bits / 8 / 1000,
        "step_ms": step * 1000,
        "time_s": step * rounds,
        "complete": bool(complete),
        "explored": explored,
        "observable": n_target,
    }


# -- the experiment grid ---------------------------------------------------------------------
def _seq(*key: int) -> np.random.SeedSequence:
    return np.random.SeedSequence([int(k) for k in key])


def trials(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Run the requested grid of trials with a progress bar; one record per run."""
    methods = args.methods
    records: list[dict[str, Any]] = []
    plan: list[tuple[float, int, Maze | None]] = []
    if args.maze_data is not None:
        plan = [(math.nan, run, args.maze_data) for run in range(args.runs)]
    else:
        plan = [(p, run, None) for p in args.p for run in range(args.runs)]
    total = sum(
        len(args.agents) * sum(1 for m in methods if _runs_for(args, m) > run) for _, run, _ in plan
    )
    done = 0
    start = time.monotonic()
    for p, run, given in plan:
        maze = (
            given
            if given is not None
            else generate_maze(
                args.size,
                p,
                np.random.default_rng(_seq(args.seed, args.size, round(p * 1000), run)),
                n_starts=max(args.agents),
            )
        )
        for n in args.agents:
            for m in methods:
                if run >= _runs_for(args, m):
                    continue
                key = (
                    args.seed,
                    args.size,
                    round(p * 1000) if p == p else 0,
                    run,
                    n,
                    list(METHODS).index(m),
                )
                rec = run_trial(maze, n, m, _seq(*key), exchanges=args.exchanges)
                rec.update(method=m, agents=n, p=None if p != p else p, run=run)
                records.append(rec)
                done += 1
                _progress(done, total, start, f"{m} n={n} p={p:g} run {run}")
    print(file=sys.stderr)
    return records


def _runs_for(args: argparse.Namespace, method: str) -> int:
    return int(min(args.runs, args.hedac_runs) if method == "hedac" else args.runs)


def _progress(done: int, total: int, start: float, what: str) -> None:
    width = 30
    fill = int(width * done / max(total, 1))
    rate = (time.monotonic() - start) / max(done, 1)
    eta = rate * (total - done)
    sys.stderr.write(
        f"\r[{'#' * fill}{'.' * (width - fill)}] {done}/{total} eta {eta:5.0f}s  {what:<32}"
    )
    sys.stderr.flush()


# -- tables, composite index, plots ----------------------------------------------------------
def _group(records: list[dict[str, Any]]) -> dict[tuple[Any, str, int], list[dict[str, Any]]]:
    groups: dict[tuple[Any, str, int], list[dict[str, Any]]] = defaultdict(list)
    for r in records:
        groups[(r["p"], r["method"], r["agents"])].append(r)
    return groups


def tables(records: list[dict[str, Any]], methods: list[str], agents: list[int]) -> str:
    """Mean ± std of every metric: one table per obstacle probability and metric."""
    groups = _group(records)
    out = []
    for p in sorted({r["p"] for r in records}, key=lambda v: -1 if v is None else -v):
        where = "given maze" if p is None else f"obstacle probability {p:g}"
        for key, label, _ in (*METRICS, *((k, lbl, False) for k, lbl in EXTRA)):
            out.append(f"\n{label} — {where}")
            out.append(f"{'method':<8} " + " ".join(f"{'n=' + str(n):>17}" for n in agents))
            for m in methods:
                cells = []
                for n in agents:
                    vals = [r[key] for r in groups.get((p, m, n), [])]
                    cells.append(f"{_fmt(vals):>17}")
                out.append(f"{m:<8} " + " ".join(cells))
        runs = {len(v) for (pp, _, _), v in groups.items() if pp == p}
        incomplete = sum(not r["complete"] for r in records if r["p"] == p)
        out.append(f"(runs per cell: {sorted(runs)}; incomplete runs: {incomplete})")
    return "\n".join(out)


def _fmt(vals: list[float]) -> str:
    if not vals:
        return "-"
    mean, std = float(np.mean(vals)), float(np.std(vals))
    digits = 0 if abs(mean) >= 100 else 2 if abs(mean) >= 1 else 4
    return f"{mean:.{digits}f} ± {std:.{digits}f}"


def composite(
    records: list[dict[str, Any]], methods: list[str], agents: list[int]
) -> dict[Any, dict[str, dict[int, float]]]:
    """Section V-B: per agent count, min-max normalise each metric's means over the methods,
    rank the methods (best gets the most points, ties share), and sum the ranks (weights 1)."""
    groups = _group(records)
    scores: dict[Any, dict[str, dict[int, float]]] = {}
    for p in {r["p"] for r in records}:
        per: dict[str, dict[int, float]] = {m: {} for m in methods}
        for n in agents:
            present = [m for m in methods if groups.get((p, m, n))]
            for m in present:
                per[m][n] = 0.0
            for key, _, higher in METRICS:
                means = np.array([np.mean([r[key] for r in groups[(p, m, n)]]) for m in present])
                lo, hi = means.min(), means.max()
                norm = (means - lo) / (hi - lo) if hi > lo else np.zeros_like(means)
                goodness = norm if higher else -norm
                for m, g in zip(present, goodness, strict=True):
                    # rank points: 1 + number beaten + half the ties
                    per[m][n] += 1 + np.sum(goodness < g) + 0.5 * (np.sum(goodness == g) - 1)
        scores[p] = per
    return scores


def composite_text(scores: dict[Any, dict[str, dict[int, float]]], agents: list[int]) -> str:
    """The composite-index table and ranking per obstacle probability."""
    out = []
    for p, per in sorted(scores.items(), key=lambda kv: -1 if kv[0] is None else -kv[0]):
        where = "given maze" if p is None else f"obstacle probability {p:g}"
        out.append(f"\ncomposite index (section V-B, higher is better) — {where}")
        out.append(
            f"{'method':<8} " + " ".join(f"{'n=' + str(n):>6}" for n in agents) + f" {'total':>7}"
        )
        totals = {m: sum(v.values()) for m, v in per.items()}
        for m in sorted(per, key=lambda m: -totals[m]):
            out.append(
                f"{m:<8} "
                + " ".join(f"{per[m].get(n, math.nan):6.1f}" for n in agents)
                + f" {totals[m]:7.1f}"
            )
        out.append("ranking: " + " > ".join(sorted(per, key=lambda m: -totals[m])))
    return "\n".join(out)


def plots(
    records: list[dict[str, Any]],
    scores: dict[Any, dict[str, dict[int, float]]],
    methods: list[str],
    agents: list[int],
    out: Path,
) -> list[Path]:
    """Figures like the paper's Fig. 8 (metrics vs agents) and Fig. 9 (composite index)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    groups = _group(records)
    ps = sorted({r["p"] for r in records}, key=lambda v: -1 if v is None else -v)
    shown = [m for m in METRICS if m[0] != "quality"]
    fig, axes = plt.subplots(
        len(shown), len(ps), figsize=(5 * len(ps), 2.6 * len(shown)), squeeze=False
    )
    for col, p in enumerate(ps):
        for row, (key, label, _) in enumerate(shown):
            ax = axes[row][col]
            for m in methods:
                xs = [n for n in agents if groups.get((p, m, n))]
                ys = [np.mean([r[key] for r in groups[(p, m, n)]]) for n in xs]
                es = [np.std([r[key] for r in groups[(p, m, n)]]) for n in xs]
                ax.errorbar(xs, ys, yerr=es, marker="o", ms=3, capsize=2, label=m)
            if key == "time_s":
                ax.set_yscale("log")
            ax.set_title(f"{label}\n{'given maze' if p is None else f'p = {p:g}'}", fontsize=8)
            ax.set_xlabel("agents", fontsize=8)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig8 = out / "maze_metrics.png"
    fig.savefig(fig8, dpi=110)
    plt.close(fig)
    fig, axes = plt.subplots(1, len(ps), figsize=(5 * len(ps), 3.5), squeeze=False)
    for col, p in enumerate(ps):
        ax = axes[0][col]
        for m in methods:
            xs = [n for n in agents if n in scores[p].get(m, {})]
            ax.plot(xs, [scores[p][m][n] for n in xs], marker="o", label=m)
        ax.set_title(f"composite index, {'given maze' if p is None else f'p = {p:g}'}")
        ax.set_xlabel("agents")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig9 = out / "maze_composite.png"
    fig.savefig(fig9, dpi=110)
    plt.close(fig)
    return [fig8, fig9]


# -- command line ----------------------------------------------------------------------------
def _csv(kind: type, choices: Any = None) -> Any:
    def parse(text: str) -> list[Any]:
        items = [kind(t) for t in text.split(",") if t.strip()]
        if choices is not None:
            bad = [i for i in items if i not in choices]
            if bad:
                raise argparse.ArgumentTypeError(
                    f"unknown {bad[0]!r}; choose from {', '.join(map(str, choices))}"
                )
        if not items:
            raise argparse.ArgumentTypeError("empty list")
        return items

    return parse


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``maze`` experiment runner."""
    parser = sub.add_parser(
        "maze",
        help="CU-LVP and baselines on seeded mazes (Linardakis et al., IV-V)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--runs", type=int, default=100, help="mazes per cell (default 100)")
    parser.add_argument(
        "--hedac-runs",
        type=int,
        default=None,
        help="fewer runs for HEDAC, the slow method (default: --runs)",
    )
    parser.add_argument("--seed", type=int, default=None, help="master seed (default: random)")
    parser.add_argument(
        "--methods",
        type=_csv(str, list(METHODS)),
        default=list(METHODS),
        help=f"comma list of {', '.join(METHODS)}",
    )
    parser.add_argument(
        "--agents",
        type=_csv(int),
        default=list(AGENT_COUNTS),
        help="comma list of agent counts (default 1,2,4,6,8,10,15,20)",
    )
    parser.add_argument("--size", type=int, default=30, help="nominal maze size (default 30)")
    parser.add_argument(
        "--p",
        type=_csv(float),
        default=list(PROBABILITIES),
        help="comma list of obstacle probabilities (default 0.85,0.15)",
    )
    parser.add_argument(
        "--exchanges",
        type=int,
        default=EXCHANGES,
        help=f"map exchanges per round (default {EXCHANGES}: two relay hops;"
        " 1: the paper's single exchange)",
    )
    parser.add_argument("--maze", type=Path, default=None, help="run on this maze JSON file")
    parser.add_argument("--out", type=Path, default=Path("out"), help="plot directory")
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    parser.add_argument(
        "--load",
        type=Path,
        action="append",
        default=[],
        metavar="FILE",
        help="tabulate the runs saved by earlier --json runs instead of running"
        " (repeatable; the last line of each file is read)",
    )
    parser.add_argument(
        "--json", action="store_true", help="end with one JSON line holding every run's figures"
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the experiment; print the seed, the tables and the composite index."""
    if args.seed is None:
        args.seed = secrets.randbits(32)
    if args.hedac_runs is None:
        args.hedac_runs = args.runs
    if args.runs < 1 or min(args.agents) < 1 or args.exchanges < 1:
        print("error: --runs, --agents and --exchanges must be positive", file=sys.stderr)
        return 2
    args.maze_data = None
    if args.maze is not None:
        try:
            args.maze_data = load_maze(args.maze)
        except MazeFileError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        if max(args.agents) > len(args.maze_data.starts):
            print(
                f"error: {args.maze} has {len(args.maze_data.starts)} starts, "
                f"{max(args.agents)} agents asked",
                file=sys.stderr,
            )
            return 2
    if args.load:
        return _report_saved(args)
    print(f"seed: {args.seed}")
    print(
        f"methods: {','.join(args.methods)}  agents: {','.join(map(str, args.agents))}  "
        f"runs: {args.runs} (hedac {min(args.runs, args.hedac_runs)})  "
        + (f"maze: {args.maze}" if args.maze else f"size: {args.size}  p: {args.p}")
        + f"  exchanges: {args.exchanges}"
    )
    records = trials(args)
    print(tables(records, args.methods, args.agents))
    scores = composite(records, args.methods, args.agents)
    print(composite_text(scores, args.agents))
    if not args.no_plots:
        for path in plots(records, scores, args.methods, args.agents, args.out):
            print(f"wrote {path}")
    if args.json:
        print(json.dumps({"seed": args.seed, "size": args.size, "runs": records}))
    return 0


def _report_saved(args: argparse.Namespace) -> int:
    records: list[dict[str, Any]] = []
    for path in args.load:
        try:
            data = json.loads(path.read_text().strip().splitlines()[-1])
        except (OSError, ValueError, IndexError) as exc:
            print(f"error: {path}: no JSON line of runs: {exc}", file=sys.stderr)
            return 2
        print(f"loaded {path}: seed {data['seed']}, {len(data['runs'])} runs")
        records.extend(
            r for r in data["runs"] if r["method"] in args.methods and r["agents"] in args.agents
        )
    methods = [m for m in args.methods if any(r["method"] == m for r in records)]
    agents = [n for n in args.agents if any(r["agents"] == n for r in records)]
    print(tables(records, methods, agents))
    scores = composite(records, methods, agents)
    print(composite_text(scores, agents))
    if not args.no_plots:
        for path in plots(records, scores, methods, agents, args.out):
            print(f"wrote {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Run as ``python -m programs.maze_experiment``."""
    parser = argparse.ArgumentParser(prog="maze_experiment")
    register(parser.add_subparsers(dest="cmd", required=True))
    args = parser.parse_args(["maze", *(sys.argv[1:] if argv is None else argv)])
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
