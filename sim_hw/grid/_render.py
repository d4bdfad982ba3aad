"""The grid world as text: what ``mover gridworld --snapshots`` writes and ``snapshot`` returns."""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from sim_hw.grid._world import GridWorld


def render_text(
    world: GridWorld, round: int, robots: Collection[int], seen: np.ndarray, target: np.ndarray
) -> str:
    """The field as text: ``#`` obstacle, ``B`` base, ``R`` resource, ``@`` robot (at the flat
    cell indices ``robots``), ``*`` trail (coloured cell), ``+`` seen by a view ray, ``.`` other
    free cells; then one line of the floor values (``-`` unmarked) per row. The header counts
    the ``target`` cells (the observable ones) that were ``seen``."""
    w, grid = world, world.grid
    occupied = set(robots)
    seen_flat = seen.ravel()
    lines = [
        f"round {round}  remaining {w.remaining}  delivered {w.delivered}  "
        f"explored {int((target & seen).sum())}/{int(target.sum())}"
    ]
    for r in range(grid.height):
        row = []
        for c in range(grid.width):
            i = r * grid.width + c
            if grid.obstacles[r, c]:
                ch = "#"
            elif i in occupied:
                ch = "@"
            elif i == w.base:
                ch = "B"
            elif w.resources[i] > 0:
                ch = "R"
            elif w.colours[i]:
                ch = "*"
            elif seen_flat[i]:
                ch = "+"
            else:
                ch = "."
            row.append(ch)
        lines.append("".join(row))
    lines.append("values:")
    for r in range(grid.height):
        vals = w.marks[r * grid.width : (r + 1) * grid.width]
        lines.append(" ".join("-" if v < 0 else str(v) for v in vals))
    return "\n".join(lines) + "\n"
