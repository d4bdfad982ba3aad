"""What a world process tells a viewer: its static scene, and a grid world's frames.

A viewer (``mover view``) is an observer of the team, not a member: it calls these on the world
and, for the pymunk world, listens to the world's state topic (``sim_hw.STATE_TOPIC``). Every
world process exports them (``sim_hw._process.serve`` calls :func:`export_scene`); they cost
nothing until a viewer calls them.

* ``view.scene()`` — the static scene. The pymunk world answers with its recording header
  (``sim_hw.continuous._record.scene_header``: arena size, obstacles, boxes, immovables,
  markers, robot radii, eye-bots on the ceiling and floor areas) and ``"kind":
  "continuous"``, so that a live view and a replay draw from the same description; a grid
  world answers with ``"kind": "grid"``, its shape, its obstacle rows (``#`` and ``.``) and
  its base cell.
* ``view.frame()`` — a grid world's state now: round, each robot's cell, the floor values
  (``-1`` unmarked), colours, resources and the cells seen. A grid world streams no state, and
  a viewer polling at a few hertz costs the world one small answer each time.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from sim_hw._lockstep import LockstepDoor
    from sim_hw.grid._server import GridStepper

SCENE = "view.scene"
"""The procedure that answers a world's static scene."""

FRAME = "view.frame"
"""The procedure that answers a grid world's state now."""


class Exports(Protocol):
    """What :func:`export_scene` needs of a node: to export a procedure by name."""

    def export(self, fn: Callable[..., Any], name: str | None = None) -> object: ...


def export_scene(node: Exports, door: LockstepDoor[Any]) -> None:
    """Export :data:`SCENE` (and, for a grid world, :data:`FRAME`) for ``door``'s world."""
    stepper = door.stepper
    if hasattr(stepper, "bots"):  # the grid world (sim_hw.grid._server.GridStepper)

        def grid_scene() -> dict[str, Any]:
            return grid_header(stepper)

        def grid_frame() -> dict[str, Any]:
            return grid_state(stepper)

        node.export(grid_scene, name=SCENE)
        node.export(grid_frame, name=FRAME)
        return
    from sim_hw.continuous._record import scene_header

    def scene() -> dict[str, Any]:
        return {**scene_header(stepper.world), "kind": "continuous"}

    node.export(scene, name=SCENE)


def grid_header(stepper: GridStepper) -> dict[str, Any]:
    """A grid world's static scene (see the module)."""
    grid, world = stepper.grid, stepper.world
    rows = ["".join("#" if o else "." for o in row) for row in grid.obstacles.tolist()]
    return {
        "type": "header",
        "kind": "grid",
        "name": "grid",
        "shape": [grid.height, grid.width],
        "obstacles": rows,
        "base": list(grid.cell(world.base)),
    }


def grid_state(stepper: GridStepper) -> dict[str, Any]:
    """A grid world's state now (see the module)."""
    grid, world = stepper.grid, stepper.world
    return {
        "tick": stepper.round,
        "robots": {name: list(grid.cell(b.cell)) for name, b in sorted(stepper.bots.items())},
        "marks": [int(v) for v in world.marks],
        "colours": [int(v) for v in world.colours],
        "resources": [int(v) for v in world.resources],
        "seen": stepper.seen.ravel().astype(int).tolist(),
    }
