"""The grid world as the lock-step door drives it, and :class:`GridServer`, a grid and its door.

:class:`GridStepper` owns the floor (values, colours, pheromone), the resources and the base of
a :class:`GridWorld`, plus the robots that joined, each on one cell; the door
(``sim_hw._lockstep``) decides when a round happens. Robots make three calls: ``join(robot,
spec)``, ``step(robot, round, action)`` and ``leave(robot)``.

Together (the default), a round's actions are applied in robot-name order (writes, loading,
unloading, pheromone, then the move; a later robot sees what an earlier one did this round);
then the pheromone diffuses, and every robot's perception for the next round is taken after all
actions, so each round is a function of the previous one and the actions.

With ``turns="sequential"`` a round is instead one iteration of Simonin et al.'s section 5.1,
as ``GridWorld.step`` runs it in process: robots act one at a time in name order, and each
robot's perception is taken just before its own turn, after the earlier robots' actions of the
round. With the same seeds, a foraging run then takes the same iterations as the in-process
runner.

The step reply also says which robots are within radio range (the radio medium knows): robots
use it to know whose broadcast of this round to wait for. ``until`` names the observer's end
of a run (``exhausted``: no resource left; ``delivered``: and all carried home; ``explored``:
every cell the robots' view rays can reach from their starts has been seen; ``never``).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypedDict, Unpack

import numpy as np

from robots.grid_hal import FREE, OBSTACLE, OCCUPIED, OFFSETS
from sim_hw._lockstep import Command, LockstepDoor, Readings
from sim_hw._process import serve
from sim_hw.grid._grid import Cell
from sim_hw.grid._maze import observable, star_view
from sim_hw.grid._render import render_text
from sim_hw.grid._sensing import hearers
from sim_hw.grid._world import GridWorld

if TYPE_CHECKING:
    from mover import Node

log = logging.getLogger("sim_hw.grid")

UNTIL = ("exhausted", "delivered", "explored", "never")


@dataclass
class _Bot:
    name: str
    cell: int
    start: int
    eight: bool = False
    view: int = 0
    carried: int = 0
    delivered: int = 0
    moved: bool = False
    moves: int = 0


class GridStepper:
    """A :class:`GridWorld`'s layers and the robots on its cells, behind the door.

    ``starts`` are placement cells handed to robots without a ``start`` in their spec, in
    name order of admission (then the base). ``exclusive`` forbids two robots on one cell (a
    move into an occupied cell fails, as in the maze papers); otherwise robots share cells
    (Simonin et al.). ``radio`` is the medium's reach in cells, measured with ``metric``
    (``manhattan`` as the maze reference code, or ``euclid``); None: every robot hears every
    other.
    """

    admits_early = False
    words = ("action", "round")

    def __init__(
        self,
        world: GridWorld,
        *,
        starts: Sequence[Cell] = (),
        exclusive: bool = False,
        radio: float | None = None,
        metric: str = "euclid",
        until: str = "exhausted",
        view: int = 2,
    ) -> None:
        if until not in UNTIL:
            raise ValueError(f"until must be one of {', '.join(UNTIL)}, got {until!r}")
        if metric not in ("manhattan", "euclid"):
            raise ValueError(f"metric must be manhattan or euclid, got {metric!r}")
        self.world = world
        self.grid = world.grid
        self.cells = world.grid.obstacles.astype(np.int8)
        self.starts = [world.grid.index(s) for s in starts]
        self.exclusive = exclusive
        self.radio = radio
        self.metric = metric
        self.until = until
        self.view = view
        self.round = 0
        self.bots: dict[str, _Bot] = {}
        self._over_at_start = False  # sequential: over() when this round began
        self.target = np.zeros(self.cells.shape, dtype=bool)
        self.seen = np.zeros(self.cells.shape, dtype=bool)
        self._readings: dict[str, Readings] = {}

    # -- the stepper protocol -------------------------------------------------------------------

    @property
    def tick(self) -> int:
        """Rounds done."""
        return self.round

    def robots(self) -> Collection[str]:
        """Names of the robots on the grid."""
        return self.bots.keys()

    def prepare(self, robot: str, spec: Mapping[str, Any] | None) -> dict[str, Any]:
        """A join's settings (``start`` [row, col], ``view`` reach, ``eight``), checked when the
        robot is placed."""
        return dict(spec or {})

    def admit(self, robot: str, prepared: dict[str, Any]) -> None:
        """Place ``robot`` on its start, the next free start, or the base."""
        taken = {b.start for b in self.bots.values()}
        free_starts = [s for s in self.starts if s not in taken]
        bot = self._place(robot, prepared, free_starts)
        self.bots[robot] = bot
        self.target |= observable(self.cells, [self.grid.cell(bot.start)], bot.view)

    def start(self) -> None:
        """Nothing to do: robots are placed in name order once the expected ones are in."""

    def advance(self, commands: Mapping[str, Command]) -> None:
        """Apply every robot's action in name order, then diffuse the pheromone."""
        for name, action in commands.items():
            self._apply(self.bots[name], action)
        self.end_round()

    def act(self, robot: str, command: Command) -> None:
        """Sequential turns: apply ``robot``'s action now."""
        self._apply(self.bots[robot], command)

    def end_round(self) -> None:
        """Diffuse the pheromone and count the round."""
        if self.world.pheromone is not None:
            self.world.pheromone.update()
        self.round += 1
        self.world.iteration = self.round

    def begin_round(self) -> None:
        """Sequential turns: note whether the run was over when this round began."""
        self._over_at_start = self.over()

    def readings(self, robot: str) -> Readings:
        """``robot``'s last perception."""
        return self._readings[robot]

    def spec_of(self, robot: str) -> dict[str, Any]:
        """What ``robot`` was placed with, and the radio medium's reach."""
        return self._spec_of(self.bots[robot])

    def remove(self, robot: str) -> None:
        """Take ``robot`` off the grid."""
        self.bots.pop(robot, None)
        self._readings.pop(robot, None)

    def sense(self) -> None:
        """Every robot's perception, after all actions of the round."""
        self._sense_all()

    def sense_one(self, robot: str) -> Readings:
        """Sequential turns: ``robot``'s perception just before its turn."""
        self._sense(self.bots[robot])
        readings = self._readings[robot]
        readings["hears"] = self._hears(robot)
        readings["over"] = self._over_at_start
        return readings

    # -- observation ------------------------------------------------------------------------------

    def over(self) -> bool:
        """Whether the observer's end of the run (``until``) is reached."""
        w = self.world
        if self.until == "exhausted":
            return w.remaining == 0
        if self.until == "delivered":
            return w.remaining == 0 and not any(b.carried for b in self.bots.values())
        if self.until == "explored":
            return bool(self.target.any()) and not (self.target & ~self.seen).any()
        return False

    def _apply(self, bot: _Bot, a: Mapping[str, Any]) -> None:
        w, c = self.world, bot.cell
        if a.get("value") is not None:
            w.marks[c] = int(a["value"])
        if a.get("colour") is not None:
            w.colours[c] = int(a["colour"])
        if a.get("load"):
            take = min(int(a["load"]), w.resources[c])
            w.resources[c] -= take
            w.remaining -= take
            bot.carried += take
        if a.get("unload") and c == w.base:
            w.delivered += bot.carried
            bot.delivered += bot.carried
            bot.carried = 0
        if a.get("drop") and w.pheromone is not None:
            w.pheromone.values[c] += float(a["drop"])
        bot.moved = False
        move = a.get("move")
        if move is not None:
            dr, dc = OFFSETS[int(move)]
            r, col = self.grid.cell(c)
            target = (r + dr, col + dc)
            if self.grid.is_free(target):
                j = self.grid.index(target)
                if not (self.exclusive and any(b.cell == j for b in self.bots.values())):
                    bot.cell = j
                    bot.moved = True
                    bot.moves += 1

    def _place(self, name: str, spec: dict[str, Any], free_starts: list[int]) -> _Bot:
        if spec.get("start") is not None:
            cell = tuple(int(v) for v in spec["start"])
            if len(cell) != 2 or not self.grid.is_free((cell[0], cell[1])):
                raise ValueError(f"start {list(cell)} of {name!r} is not a free cell")
            start = self.grid.index((cell[0], cell[1]))
        elif free_starts:
            start = free_starts.pop(0)
        else:
            start = self.world.base
        if self.exclusive and any(b.cell == start for b in self.bots.values()):
            raise ValueError(f"start {list(self.grid.cell(start))} of {name!r} is occupied")
        view = int(spec.get("view", self.view))
        return _Bot(name, start, start, bool(spec.get("eight", False)), view)

    def _spec_of(self, bot: _Bot) -> dict[str, Any]:
        return {
            "view": bot.view,
            "eight": bot.eight,
            "radio": self.radio if self.radio is not None else math.inf,
            "metric": self.metric,
        }

    def _sense_all(self) -> None:
        for bot in self.bots.values():
            self._sense(bot)
        over = self.over()
        for name in self.bots:
            self._readings[name]["hears"] = self._hears(name)
            self._readings[name]["over"] = over

    def _sense(self, bot: _Bot) -> None:
        w, grid = self.world, self.grid
        ph = w.pheromone.values if w.pheromone is not None else None
        c = bot.cell
        r, col = grid.cell(c)
        occupied = {b.cell for b in self.bots.values() if b is not bot}
        around = []
        for d, (dr, dc) in enumerate(OFFSETS[: 8 if bot.eight else 4]):
            cell = (r + dr, col + dc)
            if not grid.is_free(cell):
                around.append([d, OBSTACLE, 0, 0, 0, False, 0.0])
                continue
            j = grid.index(cell)
            state = OCCUPIED if j in occupied else FREE
            around.append(
                [
                    d,
                    state,
                    w.marks[j],
                    w.colours[j],
                    w.resources[j],
                    j == w.base,
                    float(ph[j]) if ph is not None else 0.0,
                ]
            )
        rays = []
        if bot.view > 0:
            for rr, cc, v in star_view(self.cells, (r, col), bot.view):
                rays.append([rr - r, cc - col, v])
                self.seen[rr, cc] = True
        br, bc = grid.cell(w.base)
        norm = math.hypot(br - r, bc - col)
        self._readings[bot.name] = {
            "round": self.round,
            "here": [
                w.marks[c],
                w.colours[c],
                w.resources[c],
                c == w.base,
                float(ph[c]) if ph is not None else 0.0,
            ],
            "around": around,
            "rays": rays,
            "home": [(br - r) / norm, (bc - col) / norm] if norm else [0.0, 0.0],
            "moved": bot.moved,
            "carried": bot.carried,
            "loc": [col + 0.5, r + 0.5, 0.0],
        }

    def _hears(self, name: str) -> list[str]:
        if self.radio is None:
            return sorted(n for n in self.bots if n != name)
        names = sorted(self.bots)
        cells = [self.grid.cell(self.bots[n].cell) for n in names]
        return [names[j] for j in hearers(cells, names.index(name), self.radio, self.metric)]


class GridRules(TypedDict, total=False):
    """The world's rules, :class:`GridStepper`'s keyword arguments: a :class:`GridServer` passes
    them on."""

    starts: Sequence[Cell]
    exclusive: bool
    radio: float | None
    metric: str
    until: str
    view: int


class GridServer:
    """A grid world and the lock-step door (``door``) that runs it in rounds for the robots
    that join it (see the module), with the grid's views (round, robots, state, text).

    Robots join, step and leave through ``server.door`` (:class:`LockstepDoor`): the in-process
    HAL (:func:`sim_hw.grid.in_process`) and a world process (:func:`serve_grid`) take it from
    there; what happens after a round is told to the door's ``on_tick`` hooks.
    ``expect`` robots must join before the first round; ``timeout`` wall seconds of silence in
    a round drop a robot (in process; a world process only says so, see ``sim_hw._lockstep``);
    ``turns`` is ``together`` or ``sequential``. The other arguments are :class:`GridStepper`'s.
    """

    def __init__(
        self,
        world: GridWorld,
        *,
        expect: int = 0,
        timeout: float = 2.0,
        turns: str = "together",
        **rules: Unpack[GridRules],
    ) -> None:
        self.world = world
        self.grid = world.grid
        self.stepper = GridStepper(world, **rules)
        self.door = LockstepDoor(self.stepper, expect=expect, timeout=timeout, turns=turns)

    @property
    def round(self) -> int:
        """Rounds done."""
        return self.stepper.round

    @property
    def robots(self) -> dict[str, _Bot]:
        """The robots on the grid, by name."""
        return self.stepper.bots

    def over(self) -> bool:
        """Whether the observer's end of the run (``until``) is reached."""
        return self.stepper.over()

    def state(self) -> dict[str, Any]:
        """A summary: round, robots and their cells (idle and dropped ones), resources,
        deliveries, exploration."""
        st, w = self.stepper, self.world
        bots = sorted(st.bots.items())
        return {
            "round": st.round,
            "robots": {n: list(self.grid.cell(b.cell)) for n, b in bots},
            "moves": {n: b.moves for n, b in bots},
            "dropped": list(self.door.dropped),
            "idle": sorted(self.door.idle_robots),
            "remaining": w.remaining,
            "delivered": w.delivered,
            "carried": sum(b.carried for _, b in bots),
            "observable": int(st.target.sum()),
            "explored": int((st.target & st.seen).sum()),
            "over": st.over(),
            "turns": self.door.turns,
        }

    def snapshot_text(self) -> str:
        """The field as text (see :func:`sim_hw.grid.render_text`)."""
        st = self.stepper
        cells = [b.cell for b in st.bots.values()]
        return render_text(self.world, st.round, cells, st.seen, st.target)


def serve_grid(node: Node, server: GridServer) -> None:
    """Export ``server``'s calls on ``node``: join, step, leave, and ``state`` and
    ``snapshot`` (the field as text) for tools."""
    serve(node, server.door)

    def state() -> dict[str, Any]:
        return server.state()

    def snapshot() -> str:
        return server.snapshot_text()

    node.export(state, name="state")
    node.export(snapshot, name="snapshot")
