"""The discrete grid world: a digital floor of marks and colours, resources, a base, agents.

Agents may share a cell (Simonin et al., sections 3.1 and 4.2). The floor is like an RFID floor:
each free cell holds an integer value (``UNMARKED`` until written) and a colour; the base cell
holds 0 from the start (section 3.1). One :meth:`GridWorld.step` is one iteration of section 5.1:
every agent, in index order, perceives its cell and its 4 neighbours, acts (writes, loads or
unloads) and moves; a later agent already sees what an earlier one wrote (the construction is
asynchronous). With a pheromone layer, diffusion and evaporation follow once all agents acted.

The mutable layers are flat Python lists (fast scalar access in the agents' loop) and the whole
state round-trips through :meth:`GridWorld.to_dict` (msgpack-able) so that a world process can
serve it later; :meth:`marks_array` and friends give numpy views for analysis and plots.

An ``exclusive`` world is the maze papers' (Linardakis et al., section III-A): no two agents on
one cell, a move into an occupied cell fails and the agent stays (:meth:`GridWorld.move`), and
who hears whom is :meth:`GridWorld.neighbours` (Manhattan range, as the reference code). A maze
has no base; its first start stands in, as in the grid world process.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from robots.foraging import (
    NO_COLOUR,
    UNMARKED,
    Action,
    AntNeighbour,
    AntPerception,
    Neighbour,
    Perception,
)
from sim_hw.grid._grid import OFFSETS4, Cell, Grid
from sim_hw.grid._pheromone import PheromoneField
from sim_hw.grid._sensing import hearers


class Behaviour(Protocol):
    """Anything with ``step(perception) -> Action``."""

    def step(self, p: Any, /) -> Action: ...


class GridWorld:
    """Grid, floor layers, resources, base and agent positions, stepped in-process."""

    def __init__(
        self,
        grid: Grid,
        base: Cell,
        resources: Mapping[Cell, int] | None = None,
        n_agents: int = 0,
        *,
        starts: Sequence[Cell] | None = None,
        pheromone: PheromoneField | None = None,
        exclusive: bool = False,
    ) -> None:
        if not grid.is_free(base):
            raise ValueError(f"base {base} is not a free cell")
        self.grid = grid
        h, w = grid.shape
        self.base = grid.index(base)
        n = h * w
        free = (~grid.obstacles).ravel().tolist()
        # _moves[i][d]: flat index reached from cell i in direction d, or -1 if blocked.
        self._moves: list[tuple[int, ...]] = []
        self._free_dirs: list[tuple[tuple[int, int], ...]] = []
        for i in range(n):
            r, c = divmod(i, w)
            row = []
            for dr, dc in OFFSETS4:
                rr, cc = r + dr, c + dc
                ok = 0 <= rr < h and 0 <= cc < w and free[rr * w + cc]
                row.append(rr * w + cc if ok else -1)
            self._moves.append(tuple(row))
            self._free_dirs.append(tuple((d, j) for d, j in enumerate(row) if j >= 0))
        self.marks = [UNMARKED] * n
        self.marks[self.base] = 0  # the goal cell holds 0 before agents start (section 3.1)
        self.colours = [NO_COLOUR] * n
        self.resources = [0] * n
        for cell, q in (resources or {}).items():
            if not grid.is_free(cell):
                raise ValueError(f"resource at {cell} is not on a free cell")
            self.resources[grid.index(cell)] = int(q)
        self.remaining = sum(self.resources)
        starts = list(starts) if starts is not None else [base] * n_agents
        for s in starts:
            if not grid.is_free(s):
                raise ValueError(f"agent start {s} is not a free cell")
        self.positions = [grid.index(s) for s in starts]
        self.exclusive = exclusive
        # exclusive: the cells agents stand on (a move into one of them fails)
        self._occupied: set[int] | None = set(self.positions) if exclusive else None
        if self._occupied is not None and len(self._occupied) < len(self.positions):
            raise ValueError("two agents start on one cell of an exclusive world")
        self.carried = [0] * len(self.positions)
        self.delivered = 0
        self.iteration = 0
        self.pheromone = pheromone

    # -- agents' view ---------------------------------------------------------------------------

    @property
    def n_agents(self) -> int:
        """Number of agents."""
        return len(self.positions)

    def neighbours(self, i: int, reach: float, metric: str = "euclid") -> list[int]:
        """The agents other than ``i`` within ``reach`` cells of agent ``i``: who hears its
        range-limited broadcast. ``manhattan`` counts 4-connected steps, as the maze reference
        code measures range; ``euclid`` the straight line."""
        return hearers([self.grid.cell(p) for p in self.positions], i, reach, metric)

    def perceive(self, i: int) -> Perception:
        """What marking agent ``i`` senses: its cell and its free 4-neighbours."""
        c = self.positions[i]
        marks, colours, res, base = self.marks, self.colours, self.resources, self.base
        return Perception(
            marks[c],
            colours[c],
            res[c],
            c == base,
            tuple(
                Neighbour(d, marks[j], colours[j], res[j], j == base) for d, j in self._free_dirs[c]
            ),
        )

    def perceive_ant(self, i: int) -> AntPerception:
        """What ant ``i`` senses: pheromone here and around, resources, compass to the base."""
        if self.pheromone is None:
            raise RuntimeError("this world has no pheromone layer")
        c = self.positions[i]
        ph = self.pheromone.values
        res, base = self.resources, self.base
        w = self.grid.width
        br, bc = divmod(base, w)
        r, col = divmod(c, w)
        dr, dc = br - r, bc - col
        norm = (dr * dr + dc * dc) ** 0.5
        home = (dr / norm, dc / norm) if norm else (0.0, 0.0)
        return AntPerception(
            float(ph[c]),
            res[c],
            c == base,
            tuple(AntNeighbour(d, float(ph[j]), res[j], j == base) for d, j in self._free_dirs[c]),
            home,
        )

    def apply(self, i: int, a: Action) -> None:
        """Carry out agent ``i``'s action: writes, loading, unloading, pheromone, then the move."""
        c = self.positions[i]
        if a.value is not None:
            self.marks[c] = a.value
        if a.colour is not None:
            self.colours[c] = a.colour
        if a.load:
            take = min(a.load, self.resources[c])
            self.resources[c] -= take
            self.remaining -= take
            self.carried[i] += take
        if a.unload and c == self.base:
            self.delivered += self.carried[i]
            self.carried[i] = 0
        if a.drop:
            assert self.pheromone is not None, "pheromone dropped in a world without the layer"
            self.pheromone.values[c] += a.drop
        if a.move is not None:
            j = self._moves[c][a.move]
            if j < 0:
                raise ValueError(f"agent {i} at {self.grid.cell(c)} moved into an obstacle")
            if self._occupied is None:
                self.positions[i] = j
            else:
                self.move(i, a.move)  # fails into an occupied cell

    def move(self, i: int, direction: int) -> bool:
        """Move agent ``i`` one cell in ``direction`` (0-3: north, east, south, west) unless
        that cell is an obstacle or, in an exclusive world, occupied; whether it moved."""
        if not 0 <= direction < len(OFFSETS4):
            raise ValueError(f"illegal move direction {direction!r}; 0-3 (N, E, S, W)")
        c = self.positions[i]
        j = self._moves[c][direction]
        if j < 0:
            return False
        occupied = self._occupied
        if occupied is not None:
            if j in occupied:
                return False
            occupied.discard(c)
            occupied.add(j)
        self.positions[i] = j
        return True

    def step(self, behaviours: Sequence[Behaviour], ants: bool = False) -> None:
        """One iteration: every agent perceives, acts and moves, in index order (section 5.1).

        ``ants`` selects the ant perception and runs pheromone diffusion/evaporation afterwards.
        """
        perceive = self.perceive_ant if ants else self.perceive
        apply = self.apply
        for i, b in enumerate(behaviours):
            apply(i, b.step(perceive(i)))
        if ants and self.pheromone is not None:
            self.pheromone.update()
        self.iteration += 1

    # -- progress -------------------------------------------------------------------------------

    @property
    def exhausted(self) -> bool:
        """Whether every resource cell is empty (the paper's end of foraging, section 5.1)."""
        return self.remaining == 0

    @property
    def all_delivered(self) -> bool:
        """Whether every unit has also been carried back to the base."""
        return self.remaining == 0 and not any(self.carried)

    # -- analysis -------------------------------------------------------------------------------

    def agent_cell(self, i: int) -> Cell:
        """(row, column) of agent ``i``."""
        return self.grid.cell(self.positions[i])

    def marks_array(self) -> np.ndarray:
        """The floor values as an int array (height, width); ``UNMARKED`` is -1."""
        return np.array(self.marks, dtype=np.int64).reshape(self.grid.shape)

    def colours_array(self) -> np.ndarray:
        """The floor colours as an int array (height, width)."""
        return np.array(self.colours, dtype=np.int64).reshape(self.grid.shape)

    def resources_array(self) -> np.ndarray:
        """Resource quantities as an int array (height, width)."""
        return np.array(self.resources, dtype=np.int64).reshape(self.grid.shape)

    # -- serialisation --------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The whole state as plain lists and numbers (msgpack-able)."""
        return {
            "grid": self.grid.to_dict(),
            "base": list(self.grid.cell(self.base)),
            "marks": list(self.marks),
            "colours": list(self.colours),
            "resources": list(self.resources),
            "positions": [list(self.grid.cell(p)) for p in self.positions],
            "carried": list(self.carried),
            "delivered": self.delivered,
            "iteration": self.iteration,
            "exclusive": self.exclusive,
            "pheromone": None
            if self.pheromone is None
            else {
                "values": self.pheromone.values.tolist(),
                "diffusion": self.pheromone.diffusion,
                "evaporation": self.pheromone.evaporation,
            },
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> GridWorld:
        """Inverse of :meth:`to_dict`."""
        grid = Grid.from_dict(data["grid"])
        ph = data.get("pheromone")
        field = None
        if ph is not None:
            field = PheromoneField(~grid.obstacles, ph["diffusion"], ph["evaporation"])
            field.values = np.array(ph["values"], dtype=float)
        world = cls(
            grid,
            tuple(data["base"]),
            starts=[tuple(p) for p in data["positions"]],
            pheromone=field,
            exclusive=bool(data.get("exclusive", False)),
        )
        world.marks = list(data["marks"])
        world.colours = list(data["colours"])
        world.resources = list(data["resources"])
        world.remaining = sum(world.resources)
        world.carried = list(data["carried"])
        world.delivered = int(data["delivered"])
        world.iteration = int(data["iteration"])
        return world
