"""The spatial grid under range-limited broadcasts, so that their cost grows with the
neighbourhood and not with the team.

A broadcast of range ``r`` is sent under the cell of its sender in the grid of level
``L = ceil(log2 r)``, whose cells are ``2**L >= r`` metres wide (:func:`level`, :func:`cell_of`),
so the cell size follows the ranges in use. A receiver listens, level by level, to the cells
within ``1.5 * 2**L`` of itself (:func:`cells_near`): every sender within ``r`` of it is in one of
them, with half a cell to spare, and it moves its subscriptions only once it has gone a quarter of
a cell from where it last chose them (:class:`CellSet`), declaring the new cells before dropping
the old ones. The exact distance filter stays with the receiver (:class:`mover._radio.Radio`).

Which levels a topic uses, a receiver learns from its senders' liveliness tokens (one per sender,
topic and level, see :mod:`mover._keys`); a sender sends team-wide for :data:`GRACE` seconds after
declaring its token, so that receivers have subscribed to the new level's cells before it stops.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

MIN_LEVEL = -4  # cells of 1/16 m: shorter ranges share them
MAX_LEVEL = 12  # cells of 4 km: longer ranges go team-wide
GRACE = 1.0  # seconds a sender sends team-wide after declaring a new level
MARGIN = 0.5  # receivers listen this many cells beyond the widest range of a level
MOVE = 0.25  # ... and choose their cells again after moving this many cells


class Undeclarable(Protocol):
    def undeclare(self) -> None: ...


def level(reach: float) -> int | None:
    """The grid level for broadcasts of range ``reach``, or None for team-wide."""
    if reach <= 2.0**MIN_LEVEL:
        return MIN_LEVEL
    lvl = math.ceil(math.log2(reach))
    return lvl if lvl <= MAX_LEVEL else None


def cell_of(x: float, y: float, lvl: int) -> str:
    """The name of the cell of level ``lvl`` holding ``(x, y)``."""
    size = 2.0**lvl
    return f"{math.floor(x / size)}_{math.floor(y / size)}"


def cells_near(x: float, y: float, lvl: int, radius: float) -> set[str]:
    """The cells of level ``lvl`` with a point within ``radius`` of ``(x, y)``."""
    size = 2.0**lvl
    out = set()
    for ix in range(math.floor((x - radius) / size), math.floor((x + radius) / size) + 1):
        dx = max(ix * size - x, 0.0, x - (ix + 1) * size)
        for iy in range(math.floor((y - radius) / size), math.floor((y + radius) / size) + 1):
            dy = max(iy * size - y, 0.0, y - (iy + 1) * size)
            if dx * dx + dy * dy <= radius * radius:
                out.add(f"{ix}_{iy}")
    return out


class CellSet:
    """The cells one topic's receiver listens to, level by level, moved as it moves.

    ``declare(level, cell)`` subscribes to one cell; what it returns is undeclared when the
    receiver leaves that cell's neighbourhood.
    """

    def __init__(self, declare: Callable[[int, str], Undeclarable]) -> None:
        self._declare = declare
        self._levels: dict[int, tuple[tuple[float, float] | None, dict[str, Undeclarable]]] = {}
        self.moves = 0  # times the subscriptions were chosen again

    @property
    def levels(self) -> set[int]:
        return set(self._levels)

    def cells(self, lvl: int) -> set[str]:
        """The cells listened to at level ``lvl``."""
        return set(self._levels[lvl][1]) if lvl in self._levels else set()

    def add_level(self, lvl: int, where: tuple[float, float] | None) -> None:
        """Listen to level ``lvl`` too (from ``where``, if known)."""
        if lvl not in self._levels:
            self._levels[lvl] = (None, {})
            self.follow(where)

    def follow(self, where: tuple[float, float] | None) -> None:
        """The receiver is at ``where``: listen to the cells around it."""
        if where is None:
            return  # nothing in range of an unknown place: keep what we have
        x, y = where
        for lvl, (anchor, subs) in list(self._levels.items()):
            size = 2.0**lvl
            if anchor is not None and math.hypot(x - anchor[0], y - anchor[1]) <= MOVE * size:
                continue
            want = cells_near(x, y, lvl, (1.0 + MARGIN) * size)
            kept = {c: subs[c] for c in want if c in subs}
            for cell in want - kept.keys():
                kept[cell] = self._declare(lvl, cell)
            for cell in subs.keys() - want:
                subs[cell].undeclare()
            self._levels[lvl] = ((x, y), kept)
            self.moves += 1

    def close(self, undeclare: bool) -> None:
        """Forget every cell (undeclaring them if the session is still open)."""
        for _, subs in self._levels.values():
            if undeclare:
                for sub in subs.values():
                    sub.undeclare()
        self._levels.clear()
