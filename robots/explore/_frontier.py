"""Frontier policies on the Voronoi-partitioned maze: CU-LVP and its frontier baselines.

Section III-C (CU-LVP) and section IV-B (baselines adapted to the partitioned maze as CU-LVP
is): goals are unknown cells of the agent's region, reached along wavefront paths on the
agent's own map (unknown counted as free, agents heard this round counted as obstacles).
"""

from __future__ import annotations

import math

import numpy as np

from ._agent import STAY, ExplorerAgent, Move
from ._grid import passable_mask, path_to, wavefront
from ._sensing import unexplored_in_view


def _norm(values: list[float]) -> list[float]:
    """Min-max normalisation N(x) of equation (1); all-equal values map to 0."""
    lo, hi = min(values), max(values)
    if hi == lo:
        return [0.0] * len(values)
    return [(v - lo) / (hi - lo) for v in values]


def _manhattan(a: int, b: int, width: int) -> int:
    ar, ac = divmod(a, width)
    br, bc = divmod(b, width)
    return abs(ar - br) + abs(ac - bc)


class FrontierPolicy:
    """Shared goal keeping: hold a goal until it is explored, then pick another (III-C)."""

    name = "frontier"
    hold_goal = True

    def decide(self, agent: ExplorerAgent) -> Move:
        """Keep or re-plan the goal inside the agent's region, then step towards it.

        Agents in range are obstacles for choosing a new goal (III-C). For moving, an agent
        plans around the agents heard with smaller ids only, and waits when one stands in its
        way (III-C: "it remains stationary until the obstructing agents move"); after two
        blocked rounds it re-plans around every agent heard. This priority keeps two agents
        from dancing around each other, and a blocked group from waiting forever.
        """
        cand = agent.candidates()
        if not cand.any() and not agent.switch_region():
            agent.goal = None
            return STAY
        cand = agent.candidates()
        stuck = agent.stuck >= 2
        ahead = agent.peer_cells() if stuck else agent.senior_peer_cells()
        passable = passable_mask(agent.known, ahead)
        self.gain = self.path_gain(agent)
        goal = agent.goal
        if (
            self.hold_goal
            and not stuck
            and goal is not None
            and cand[goal]
            and self.keep(agent, goal)
        ):
            move = agent.step_towards(goal, passable, self.gain)
            if move is not None:
                return move
        goal = self.select(agent, cand, passable_mask(agent.known, agent.peer_cells()))
        if goal is None:
            goal = self.select(agent, cand, passable)
        if goal is not None:
            agent.goal = goal
            move = agent.step_towards(goal, passable, self.gain)
            if move is not None:
                return move
            agent.stuck += 1
            return agent.sidestep() if stuck else STAY
        goal = self.select(agent, cand, passable_mask(agent.known))
        if goal is not None:  # every candidate lies behind other agents: wait for them
            agent.goal = goal
            agent.stuck += 1
            return agent.sidestep() if stuck else STAY
        agent.goal = None  # the rest of the region cannot be reached: move on
        if not agent.switch_region(exclude_current=True):
            return STAY
        return self.decide(agent)

    gain: list[int] | None = None  # this decision's path gain per cell (``path_gain``)

    def keep(self, agent: ExplorerAgent, goal: int) -> bool:
        """Whether a still-unknown goal stays this agent's (overridden by CU-LVP)."""
        return True

    def path_gain(self, agent: ExplorerAgent) -> list[int] | None:
        """Per cell, what a path gains by crossing it (None: any shortest path will do)."""
        return None

    def select(self, agent: ExplorerAgent, cand: np.ndarray, passable: bytearray) -> int | None:
        """Pick a goal among the candidate cells, or None if none is reachable."""
        raise NotImplementedError


class _AmongNearest(FrontierPolicy):
    """A policy that picks among the nearest candidates (by wavefront distance)."""

    def select(self, agent: ExplorerAgent, cand: np.ndarray, passable: bytearray) -> int | None:
        """One of the nearest candidates (:meth:`pick`), or None if none is reachable."""
        _, _, found = wavefront(
            passable, agent.pos, agent.width, bytearray(cand.tobytes()), nearest_only=True
        )
        return self.pick(agent, found) if found else None

    def pick(self, agent: ExplorerAgent, found: list[int]) -> int:
        """The goal among the nearest candidates ``found`` (not empty)."""
        raise NotImplementedError


class NearestFrontier(_AmongNearest):
    """Yamauchi's nearest frontier [29]: the closest unknown cell; ties broken at random."""

    name = "nf"

    def pick(self, agent: ExplorerAgent, found: list[int]) -> int:
        """A nearest candidate drawn at random."""
        return found[int(agent.rng.integers(len(found)))]


class CostUtilityMNM(_AmongNearest):
    """CU-MNM [30]: among the nearest frontiers, the one farthest (summed) from the others."""

    name = "cu-mnm"

    def pick(self, agent: ExplorerAgent, found: list[int]) -> int:
        """Nearest frontiers, ranked by the summed distance to the agents heard."""
        others = agent.peer_cells()
        return max(sorted(found), key=lambda f: sum(_manhattan(f, o, agent.width) for o in others))


class CostUtilityJGR(FrontierPolicy):
    """CU-JGR [31]: maximise U(a) - λ C(a); U = Unex(a, R)/(π R²), C = L(a)/max L; λ = 0.8."""

    name = "cu-jgr"

    def __init__(self, lam: float = 0.8, reach: int = 2) -> None:
        self.lam = lam
        self.reach = reach

    def select(self, agent: ExplorerAgent, cand: np.ndarray, passable: bytearray) -> int | None:
        """Every reachable candidate, scored by expected gain against path length."""
        dist, _, found = wavefront(passable, agent.pos, agent.width, bytearray(cand.tobytes()))
        if not found:
            return None
        unex = unexplored_in_view(agent.known, self.reach).ravel()
        longest = max(dist[f] for f in found)
        area = math.pi * self.reach**2
        return max(sorted(found), key=lambda f: unex[f] / area - self.lam * dist[f] / longest)


class CostUtilityBSO(FrontierPolicy):
    """CU-BSO [32]: the frontier with the fewest agents nearer to it than this one.

    Costs are wavefront distances; the agents counted are those heard this round. Unlike the
    reference implementation, which re-assigns every round with every agent's position, the
    goal is held until explored: re-choosing every round from range-limited knowledge made
    agents at the edge of each other's range switch goals back and forth forever.
    """

    name = "cu-bso"

    def select(self, agent: ExplorerAgent, cand: np.ndarray, passable: bytearray) -> int | None:
        """Minimise P_ij (agents closer to the frontier), then own cost."""
        free_way = passable_mask(agent.known)
        own, _, found = wavefront(passable, agent.pos, agent.width, bytearray(cand.tobytes()))
        if not found:
            return None
        idx = np.array(found)
        mine = np.array(own)[idx]
        closer = np.zeros(len(idx), dtype=np.int32)
        for p in agent.peer_cells():
            theirs = np.array(wavefront(free_way, p, agent.width)[0])[idx]
            closer += (theirs >= 0) & (theirs < mine)
        order = np.lexsort((idx, mine, closer))
        return int(idx[order[0]])


class CULVP(FrontierPolicy):
    """CU-LVP (section III): nearest frontiers of the region, ties by utility (1).

    utility(f) = N(u_mnm(f)) + λ N(u_jgr(f)), λ = 0.2; u_mnm (2) sums the distances from f to
    every agent known this round (itself included); u_jgr (3) sums Unex(x, r) over the whole
    wavefront path to f, taking of the shortest paths one that sees the most, which is also
    the path the agent walks (``path_gain``). Goals held by agents in range are excluded while
    there are at least as many candidates as agents; a goal another agent in range also holds
    is given up by the agent with the larger id, and a goal explored by anyone is re-planned.

    Beyond the paper, u_mnm also counts the agents not in range whose news is at most
    ``news_rounds`` rounds old, at the cell they were then: every message passes on the
    sender's latest news of each agent (round, cell, regions; ``ExplorerAgent._merge_news``)
    that changed since its last message (all of it to a newcomer; ``news_whole``: all of it in
    every message), so an agent also steers away from agents its neighbours heard lately.
    """

    name = "cu-lvp"
    region_choice = "estimate"  # see ExplorerAgent.switch_region
    partition = "balanced"  # regions of about equal size: see balanced_partition
    news_rounds = 10  # agents out of range counted in u_mnm while their news is this fresh
    reconsider_every = 3  # a helper chooses its region again this often (rounds; 0: never)
    help_share = 0.5  # each other agent lately known to hold a region takes this share of it
    news_whole = False  # True: every message passes on all the news (not what changed)

    def __init__(self, lam: float = 0.2, reach: int = 2) -> None:
        self.lam = lam
        self.reach = reach

    def decide(self, agent: ExplorerAgent) -> Move:
        """A helper first reconsiders its region (``reconsider_every``), then as the base."""
        if self.reconsider_every > 0:
            agent.reconsider(self.reconsider_every)
        return super().decide(agent)

    def keep(self, agent: ExplorerAgent, goal: int) -> bool:
        """Give the goal up if a heard agent with a smaller id holds it too."""
        return not any(p.goal == goal and pid < agent.id for pid, p in agent.peers.items())

    def path_gain(self, agent: ExplorerAgent) -> list[int] | None:
        """Unex(x, r) of every cell: u_jgr (3) is summed over the path to a frontier, and of
        the shortest paths the one scored, and walked, is the one that sees the most."""
        return unexplored_in_view(agent.known, self.reach).ravel().tolist()

    def select(self, agent: ExplorerAgent, cand: np.ndarray, passable: bytearray) -> int | None:
        """Nearest frontiers (BFS wavefront), highest utility among ties."""
        held = [p.goal for p in agent.peers.values() if p.goal is not None]
        targets = cand
        if held and int(cand.sum()) >= len(agent.peers) + 1:
            targets = cand.copy()
            targets[held] = False
        gain = self.gain if self.gain is not None else self.path_gain(agent)
        assert gain is not None
        _, parent, found = wavefront(
            passable,
            agent.pos,
            agent.width,
            bytearray(targets.tobytes()),
            nearest_only=True,
            gain=gain,
        )
        if not found:
            return None
        if len(found) == 1:
            return found[0]
        found.sort()
        agents = [agent.pos, *agent.peer_cells()]
        if self.news_rounds > 0:
            agents += agent.recent_cells(self.news_rounds)
        mnm = [float(sum(_manhattan(f, a, agent.width) for a in agents)) for f in found]
        jgr = [
            float(gain[agent.pos] + sum(gain[x] for x in path_to(parent, agent.pos, f)))
            for f in found
        ]
        score = [a + self.lam * b for a, b in zip(_norm(mnm), _norm(jgr), strict=True)]
        return found[int(np.argmax(score))]
