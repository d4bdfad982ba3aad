"""HEDAC on the partitioned maze (Crnković et al. [25]; adaptation of section IV-B).

The attracting field u solves, by ``iterations`` Jacobi sweeps,

    u_ij = (Σ_l a_ij(l) u_l + s_ij) / (Σ_l a_ij(l) + α),   s_ij = max(0, 1 - c_ij) · S,

with a_ij(l) = 1 for a passable neighbour, c_ij = 1 on explored cells and S the number of
explored cells (the reference implementation's choices). Section IV-B: only the agent's
region counts, unknown cells outside it are obstacles for the field; an agent moves to the
neighbour of largest u, never onto a cell an agent heard this round stands on (anti-collision
on). When the field gives no pull (region beyond reach of the field), the agent follows the
wavefront path to its nearest frontier, as the paper's refinement does. It does the same, until
that frontier is explored, when climbing the field has it going back and forth between two
cells without learning anything (the field changes with the other agents' positions, and a
team can fall into such a cycle together and stay in it).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ._agent import STAY, ExplorerAgent, Move
from ._grid import FREE, UNKNOWN, passable_mask, wavefront


def attracting_field(
    open_: np.ndarray, source: np.ndarray, alpha: float, iterations: int
) -> np.ndarray:
    """Jacobi iterations of the HEDAC linear system on the cells ``open_``."""
    openf = open_.astype(np.float64)
    den = np.zeros(open_.shape)
    den[1:, :] += openf[:-1, :]
    den[:-1, :] += openf[1:, :]
    den[:, 1:] += openf[:, :-1]
    den[:, :-1] += openf[:, 1:]
    den += alpha
    u = np.zeros(open_.shape)
    acc = np.empty(open_.shape)
    for _ in range(iterations):
        acc[:] = source
        acc[1:, :] += u[:-1, :]
        acc[:-1, :] += u[1:, :]
        acc[:, 1:] += u[:, :-1]
        acc[:, :-1] += u[:, 1:]
        np.divide(acc, den, out=u)
        u *= openf  # closed cells hold no heat, so a_ij(l) u_l = u_l for every neighbour l
    return u


class Hedac:
    """HEDAC with α = 10, 100 iterations and anti-collision, confined to the agent's region."""

    name = "hedac"

    def __init__(self, alpha: float = 10.0, iterations: int = 100) -> None:
        self.alpha = alpha
        self.iterations = iterations
        self._trail: deque[tuple[int, int]] = deque(maxlen=4)  # (cell, cells known) per round
        self._pursue = False  # following the wavefront path out of a cycle

    def _cycling(self, pos: int, explored: int) -> bool:
        """Whether the last four rounds went a, b, a, b with nothing learnt."""
        trail = self._trail
        trail.append((pos, explored))
        if (
            len(trail) == 4
            and trail[0][0] == trail[2][0]
            and trail[1][0] == trail[3][0]
            and trail[0][1] == explored
        ):
            trail.clear()
            return True
        return False

    def decide(self, agent: ExplorerAgent) -> Move:
        """Climb the attracting field; fall back to the nearest frontier's wavefront path."""
        cand = agent.candidates()
        if not cand.any() and not agent.switch_region():
            return STAY
        cand = agent.candidates()
        known = agent.known.ravel()
        explored = int(np.count_nonzero(known != UNKNOWN))
        if self._cycling(agent.pos, explored):
            self._pursue, agent.goal = True, None
        elif self._pursue and agent.goal is not None and not cand[agent.goal]:
            self._pursue = False  # the frontier it went for is explored: back to the field
        peers = agent.peer_cells()
        w = agent.width
        if not self._pursue:
            open_ = (known == FREE) | cand
            open_[peers] = False
            u = attracting_field(
                open_.reshape(agent.shape),
                (cand * float(explored)).reshape(agent.shape),
                self.alpha,
                self.iterations,
            ).ravel()
            best, best_u = -1, 0.0
            for k in (agent.pos - w, agent.pos + w, agent.pos - 1, agent.pos + 1):
                if open_[k] and u[k] > best_u:
                    best, best_u = k, float(u[k])
            if best >= 0:
                agent.goal = None
                return agent.move_to(best)
        targets = bytearray(cand.tobytes())
        for blocked in (peers, []):
            passable = passable_mask(agent.known, blocked)
            _, _, found = wavefront(passable, agent.pos, w, targets, nearest_only=True)
            if found:
                agent.goal = min(found)
                move = agent.step_towards(agent.goal, passable)
                if move is None or (move == STAY and agent.stuck >= 2):
                    return agent.sidestep()
                return move
        # the rest of the region cannot be reached: move on
        return self.decide(agent) if agent.switch_region(exclude_current=True) else STAY
