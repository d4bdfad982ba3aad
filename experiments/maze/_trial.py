"""Seeded maze trials in-process: the agents' rounds driven in lock-step over a maze world.

Each trial builds a maze (section IV-A), puts N agents on its first N start cells, and runs
rounds until the union of the agents' maps knows every inner cell the agents can see (an
observer measures it; the agents never see it). The rounds are :func:`robots.explore.
explore_rounds`, the same the robot program ``programs.explore_maze`` drives; here every
agent's is resumed phase by phase: all sense; all broadcast (msgpack, delivered to the agents
within range and decoded from the bytes) and hear; the relays among those that heard anyone;
then the moves, in agent order (a move into an occupied cell fails).

Metrics (section IV-C): rounds, exploration cost (4-connected moves made), efficiency
M / cost, map quality (M - errors) / P, communication (bytes actually sent, relays included,
beside the paper's equation (8)), and computation time per agent step (equation (4) uses its
mean times rounds; it is the only figure that is not a function of the seeds).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

from robots.explore import (
    EXCHANGES,
    METHODS,
    Drive,
    Exchange,
    ExplorerAgent,
    Request,
    View,
    explore_rounds,
    make_team,
)
from robots.grid_hal import direction_of
from sim_hw.grid import Maze, broadcast_range, generate_maze, maze_world, observable, star_view

from .._common import Progress
from .._saved import Record, load_runs, run_pool
from ._settings import MazeSettings


@dataclass
class _Tally:
    rounds: int = 0
    cost: int = 0
    sent: int = 0  # msgpack bytes of every message sent
    heard: int = 0  # of the messages someone was in range of
    paper_bits: int = 0
    busy: float = 0.0  # seconds spent in the agents (deciding, packing)


def run_trial(
    maze: Maze,
    n_agents: int,
    method: str,
    seed: np.random.SeedSequence,
    max_rounds: int | None = None,
    exchanges: int = EXCHANGES,
    partition: str = "balanced",
    news: str = "on",
) -> dict[str, Any]:
    """One seeded exploration run; returns its metrics (section IV-C). ``exchanges`` is the
    number of map exchanges per round (:data:`robots.explore.EXCHANGES`; 1: the paper's);
    ``partition``, CU-LVP's regions (:data:`robots.explore.PARTITIONS`); ``news``, how
    CU-LVP's agents pass on each other's news (:func:`robots.explore.make_policy`)."""
    world = maze_world(maze, n_agents)
    cells = [world.agent_cell(i) for i in range(n_agents)]
    team = make_team(method, maze.shape, cells, seed, partition, news)
    target = observable(maze.grid, cells)
    n_target = int(target.sum())
    known = np.zeros(maze.shape, dtype=bool)
    covered = 0
    rows, cols = maze.shape
    reach = broadcast_range(maze.shape)
    cap = max_rounds if max_rounds is not None else 5 * rows * cols  # a stuck team is reported
    tally = _Tally()
    plans = [explore_rounds(agent, exchanges) for agent in team]
    asks: list[Request | None] = [None] * n_agents

    def resume(i: int, reply: Any) -> None:
        t0 = time.perf_counter()
        try:
            asks[i] = plans[i].send(reply)
        except StopIteration:
            asks[i] = None
        tally.busy += time.perf_counter() - t0

    for i in range(n_agents):
        resume(i, None)  # each asks to sense
    while True:
        cells = [world.agent_cell(i) for i in range(n_agents)]
        views = [star_view(maze.grid, cell) for cell in cells]
        for seen in views:
            for r, c, _ in seen:
                if target[r, c] and not known[r, c]:
                    known[r, c] = True
                    covered += 1
        over = covered >= n_target or tally.rounds >= cap
        for i in range(n_agents):
            resume(i, View(views[i], cells[i], over))
        if over:
            break
        hearers = [world.neighbours(i, reach, "manhattan") for i in range(n_agents)]
        pairs = sum(j > i for i in range(n_agents) for j in hearers[i])
        tally.paper_bits += pairs * 4 * rows * cols  # eq. (8) per communicating pair
        while any(isinstance(a, Exchange) for a in asks):  # the round's message, then relays
            inbox = _deliver(asks, hearers, tally)
            for i, a in enumerate(asks):
                if isinstance(a, Exchange):
                    resume(i, inbox[i])
        for i, a in enumerate(asks):
            assert isinstance(a, Drive), a
            d = direction_of(*a.move)
            if d is not None and world.move(i, d):
                tally.cost += 1
            resume(i, None)
        tally.rounds += 1
    return _metrics(maze, team, tally, covered >= n_target, n_target)


def _deliver(
    asks: list[Request | None], hearers: list[list[int]], tally: _Tally
) -> list[list[dict[str, Any]]]:
    """Every message asked to be exchanged, packed with msgpack and delivered decoded to the
    agents in its sender's range, in sender order."""
    inbox: list[list[dict[str, Any]]] = [[] for _ in asks]
    for i, a in enumerate(asks):
        if not isinstance(a, Exchange):
            continue
        t0 = time.perf_counter()
        packed = msgpack.packb(a.message)
        tally.busy += time.perf_counter() - t0
        tally.sent += len(packed)
        if hearers[i]:
            tally.heard += len(packed)
            msg = msgpack.unpackb(packed)
            for j in hearers[i]:
                inbox[j].append(msg)
    return inbox


def _metrics(
    maze: Maze, team: list[ExplorerAgent], t: _Tally, complete: bool, n_target: int
) -> dict[str, Any]:
    union = np.full(maze.shape, -1, dtype=np.int8)
    for agent in team:
        unknown = union == -1
        union[unknown] = agent.known[unknown]
    inner = (slice(1, -1), slice(1, -1))
    u, g = union[inner], maze.grid[inner]
    explored = int(np.count_nonzero(u != -1))
    errors = int(np.count_nonzero((u != -1) & (u != g)))
    steps = max(1, (t.rounds + 1) * len(team))
    step = t.busy / steps
    return {
        "rounds": t.rounds,
        "cost": t.cost,
        "efficiency": explored / max(t.cost, 1),
        "quality": (explored - errors) / u.size,
        "comm_kB": t.heard / 1000,
        "comm_sent_kB": t.sent / 1000,
        "comm_paper_kB": t.paper_bits / 8 / 1000,
        "step_ms": step * 1000,
        "time_s": step * t.rounds,
        "complete": bool(complete),
        "explored": explored,
        "observable": n_target,
    }


# -- the experiment grid ---------------------------------------------------------------------
def _seq(*key: int) -> np.random.SeedSequence:
    return np.random.SeedSequence([int(k) for k in key])


Job = tuple[MazeSettings, float, int, int, str]
"""One run: the settings, the obstacle probability (NaN: the given maze), the run index, the
agent count and the method."""


def jobs(s: MazeSettings) -> list[Job]:
    """Every run of the grid, in the order its records are reported."""
    ps = [math.nan] if s.maze is not None else list(s.p)
    return [
        (s, p, run, n, m)
        for p in ps
        for run in range(s.runs)
        for n in s.agents
        for m in s.methods
        if run < s.runs_for(m)
    ]


def one_run(job: Job) -> dict[str, Any]:
    """The record of one run. The maze of run k at probability p is the same for every agent
    count and method (its seed is the master seed, the size, p and k); the agents' seed adds
    the agent count and the method."""
    s, p, run, n, m = job
    code = 0 if math.isnan(p) else round(p * 1000)
    maze = s.maze
    if maze is None:
        rng = np.random.default_rng(_seq(s.seed, s.size, code, run))
        maze = generate_maze(s.size, p, rng, n_starts=max(s.agents))
    key = (s.seed, s.size, code, run, n, list(METHODS).index(m))
    rec = run_trial(
        maze, n, m, _seq(*key), exchanges=s.exchanges, partition=s.partition, news=s.news
    )
    rec.update(method=m, agents=n, p=_p(p), run=run, seed=s.seed)
    return rec


def point_file(s: MazeSettings, method: str, agents: int, p: float | None) -> Path:
    """The file of one point's runs under ``s.save``: the method, agent count, maze (size and
    p, or the maze file's name), exchanges and CU-LVP's plain partition and news (off, or whole
    in every message) name it, so that other settings save apart (CU-LVP's runs before the
    balanced partition used the file's name without ``-voronoi``, its runs before the news
    without ``-nonews``, its runs with the whole news in every message, before 2026-12-04
    15:30 UTC, without ``-wholenews``)."""
    assert s.save is not None
    where = f"file-{s.maze_path.stem}" if s.maze_path is not None else f"s{s.size}-p{p:g}"
    plain = "-voronoi" if method == "cu-lvp" and s.partition == "voronoi" else ""
    quiet = (
        {"on": "", "off": "-nonews", "whole": "-wholenews"}[s.news] if method == "cu-lvp" else ""
    )
    return s.save / f"{method}-n{agents}-{where}-x{s.exchanges}{plain}{quiet}.jsonl"


def describe(job: Job) -> str:
    """A run as a failure names it: enough to make it again."""
    s, p, run, n, m = job
    return f"{m} n={n} p={p:g} run {run} (--seed {s.seed} --size {s.size})"


def trials(settings: MazeSettings) -> list[dict[str, Any]]:
    """The requested grid of trials, one record per run in grid order: the runs saved under
    ``settings.save`` with its seed, the missing ones made on its executor and saved as they
    finish, then read back from the files with the rest (kept as made when nothing is saved)."""
    s = settings
    todo = jobs(s)
    have = _saved(s, todo)
    missing = [j for j in todo if j[2] not in have.get((j[4], j[3], _p(j[1])), {})]
    kept: list[Record] = []  # the runs made, when no file keeps them
    run_pool(
        missing,
        one_run,
        workers=s.workers,
        save_to=None
        if s.save is None
        else lambda r: point_file(s, r["method"], r["agents"], r["p"]),
        bar=Progress(len(missing)),
        status=lambda r: f"{r['method']} n={r['agents']} p={r['p']} run {r['run']}",
        on=s.executor,
        describe=describe,
        each=kept.append if s.save is None else None,
    )
    if missing and s.save is not None:
        have = _saved(s, todo)
    records = [
        r for per in have.values() for r in per.values() if r["run"] < s.runs_for(r["method"])
    ]
    records += kept
    order = {(m, n, _p(p), run): i for i, (_, p, run, n, m) in enumerate(todo)}
    records.sort(key=lambda r: order[r["method"], r["agents"], r["p"], r["run"]])
    return records


def _saved(
    s: MazeSettings, todo: list[Job]
) -> dict[tuple[str, int, float | None], dict[int, Record]]:
    """The runs saved under ``s.save`` with ``s.seed`` for the points of ``todo``, by point
    (method, agent count, obstacle probability) and run index."""
    have: dict[tuple[str, int, float | None], dict[int, Record]] = {}
    if s.save is not None:
        for _, p, _, n, m in todo:
            if (m, n, _p(p)) not in have:
                have[m, n, _p(p)] = load_runs(point_file(s, m, n, _p(p)), s.seed)
    return have


def _p(p: float) -> float | None:
    """A record's obstacle probability: None for the given maze's (NaN in a job)."""
    return None if math.isnan(p) else p
