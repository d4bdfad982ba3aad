"""The grid world's clock and its door: lock-step rounds over a :class:`GridWorld`'s layers.

A :class:`GridServer` owns the floor (values, colours, pheromone), the resources and the base
of a ``GridWorld``, plus the robots that joined, each on one cell. Robots make three calls:
``join(robot, spec)``, ``step(robot, round, action)`` and ``leave(robot)``; the world process
exports them over a mover node (:func:`serve_grid`).

A round advances only when every robot in the world has handed in its action for it. Actions
are applied in robot-name order (writes, loading, unloading, pheromone, then the move; a later
robot sees what an earlier one did this round); then the pheromone diffuses. Every robot's
perception for the next round is taken after all actions, so each round is a function of the
previous one and the actions: runs are reproducible. A robot that has not answered ``timeout``
wall seconds after the first action of a round arrived is dropped, with a log line, and the
round goes on without it; a robot whose process leaves the team is dropped at once.

With ``turns="sequential"`` a round is instead one iteration of Simonin et al.'s section 5.1,
as ``GridWorld.step`` runs it in process: robots act one at a time in name order, and each
robot's perception is taken just before its own turn, after the earlier robots' actions of the
round (so a robot's reply comes once the robot before it has acted in the next round). With the
same seeds, a foraging run then takes the same iterations as the in-process runner.

The step reply also says which robots are within radio range (the radio medium knows): robots
use it to know whose broadcast of this round to wait for. ``until`` names the observer's end
of a run (``exhausted``: no resource left; ``delivered``: and all carried home; ``explored``:
every cell the robots' view rays can reach from their starts has been seen; ``never``).
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from robots.grid_hal import FREE, OBSTACLE, OCCUPIED, OFFSETS
from sim_hw.grid._grid import Cell
from sim_hw.grid._maze import observable, star_view
from sim_hw.grid._world import GridWorld

log = logging.getLogger("sim_hw.grid._server")

UNTIL = ("exhausted", "delivered", "explored", "never")
Readings = dict[str, Any]


class RobotDropped(LookupError):
    """The robot is not (or no longer) in the grid world."""


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


class GridServer:
    """Runs a grid world in lock-step rounds for the robots that join it.

    ``starts`` are placement cells handed to robots without a ``start`` in their spec, in
    name order of admission (then the base). ``exclusive`` forbids two robots on one cell (a
    move into an occupied cell fails, as in the maze papers); otherwise robots share cells
    (Simonin et al.). ``radio`` is the medium's reach in cells, measured with ``metric``
    (``manhattan`` as the maze reference code, or ``euclid``); None: every robot hears every
    other. ``expect`` robots must join before the first round.
    """

    def __init__(
        self,
        world: GridWorld,
        *,
        starts: Sequence[Cell] = (),
        exclusive: bool = False,
        radio: float | None = None,
        metric: str = "euclid",
        until: str = "exhausted",
        expect: int = 0,
        timeout: float = 2.0,
        view: int = 2,
        turns: str = "together",
    ) -> None:
        if turns not in ("together", "sequential"):
            raise ValueError(f"turns must be together or sequential, got {turns!r}")
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
        self.expect = expect
        self.timeout = timeout
        self.view = view
        self.turns = turns
        self.round = 0
        self._acted: set[str] = set()  # sequential: who has acted in this round
        self._over_at_start = False  # sequential: over() when this round began
        self.robots: dict[str, _Bot] = {}
        self.dropped: list[str] = []
        self._started = expect <= 0
        self._joins: dict[str, tuple[dict[str, Any], asyncio.Future[dict[str, Any]]]] = {}
        self._actions: dict[str, dict[str, Any]] = {}
        self._waiters: dict[str, asyncio.Future[Readings]] = {}
        self._deadline: asyncio.TimerHandle | None = None
        self._target = np.zeros(self.cells.shape, dtype=bool)
        self._seen = np.zeros(self.cells.shape, dtype=bool)
        self._readings: dict[str, Readings] = {}
        #: Called with the server after every round (snapshots, recorders).
        self.on_round: Callable[[GridServer], None] | None = None

    # -- the three calls ----------------------------------------------------------------------

    async def join(self, robot: str, spec: dict[str, Any] | None = None) -> dict[str, Any]:
        """Place ``robot`` (spec: ``start`` [row, col], ``view`` reach, ``eight``); returns
        ``{"spec", "readings"}`` once it is in the world. A repeated join gets the same answer."""
        if robot in self._joins:
            return await asyncio.shield(self._joins[robot][1])
        if robot in self.robots:
            return {"spec": self._spec_of(self.robots[robot]), "readings": self._readings[robot]}
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._joins[robot] = (dict(spec or {}), future)
        if not self._started and len(self._joins) + len(self.robots) >= self.expect:
            self._started = True
        if self._started and not self._actions:  # at a round boundary: admit now
            self._resolve(self._admit())
        return await future

    async def step(self, robot: str, round: int, action: dict[str, Any]) -> Readings:
        """Hand in ``robot``'s action for round ``round``; returns its next perception.

        An action for a round already done is a retry whose reply was lost: it gets the
        current perception and is not applied again.
        """
        if robot not in self.robots:
            raise RobotDropped(f"robot {robot!r} is not in the grid world")
        if self.turns == "sequential":
            return await self._step_in_turn(robot, round, action)
        if round < self.round:
            return self._readings[robot]
        self._actions[robot] = action or {}
        waiter = self._waiters.get(robot)
        if waiter is None:
            waiter = self._waiters[robot] = asyncio.get_running_loop().create_future()
        self._maybe_step()
        if not waiter.done() and self._deadline is None:
            self._deadline = asyncio.get_running_loop().call_later(self.timeout, self._expire)
        return await asyncio.shield(waiter)  # shared with retries: see WorldServer.step

    async def leave(self, robot: str) -> None:
        """Take ``robot`` out of the world."""
        self._remove(robot)
        self._maybe_step()

    def drop(self, robot: str, why: str) -> None:
        """Take ``robot`` out now (e.g. its process left the team), with a log line."""
        if robot in self.robots or robot in self._joins:
            log.warning("robot %s %s: dropped at round %d", robot, why, self.round)
            self.dropped.append(robot)
            self._remove(robot)
            self._maybe_step()

    # -- observation (for tools and tests) ------------------------------------------------------

    def over(self) -> bool:
        """Whether the observer's end of the run (``until``) is reached."""
        w = self.world
        if self.until == "exhausted":
            return w.remaining == 0
        if self.until == "delivered":
            return w.remaining == 0 and not any(b.carried for b in self.robots.values())
        if self.until == "explored":
            return bool(self._target.any()) and not (self._target & ~self._seen).any()
        return False

    def state(self) -> dict[str, Any]:
        """A summary: round, robots and their cells, resources, deliveries, exploration."""
        w = self.world
        return {
            "round": self.round,
            "robots": {n: list(self.grid.cell(b.cell)) for n, b in sorted(self.robots.items())},
            "moves": {n: b.moves for n, b in sorted(self.robots.items())},
            "dropped": list(self.dropped),
            "remaining": w.remaining,
            "delivered": w.delivered,
            "carried": sum(b.carried for b in self.robots.values()),
            "observable": int(self._target.sum()),
            "explored": int((self._target & self._seen).sum()),
            "over": self.over(),
            "turns": self.turns,
        }

    # -- stepping -----------------------------------------------------------------------------

    def _maybe_step(self) -> None:
        if self.turns == "sequential":
            self._pump()
            return
        if self.robots and len(self._actions) >= len(self.robots):
            self._advance()
        elif not self.robots and self._joins:  # the last robot left while others joined
            self._resolve(self._admit())

    def _advance(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        actions, self._actions = self._actions, {}
        for name in sorted(actions):
            if name in self.robots:
                self._apply(self.robots[name], actions[name])
        if self.world.pheromone is not None:
            self.world.pheromone.update()
        self.round += 1
        self.world.iteration = self.round
        admitted = self._admit()
        self._sense_all()
        self._resolve(admitted)
        waiters, self._waiters = self._waiters, {}
        for name, waiter in waiters.items():
            if not waiter.done() and name in self.robots:
                waiter.set_result(self._readings[name])
        if self.on_round is not None:
            self.on_round(self)

    # -- sequential turns -------------------------------------------------------------------

    async def _step_in_turn(self, robot: str, round: int, action: dict[str, Any]) -> Readings:
        waiter = self._waiters.get(robot)
        if round < self.round or (round == self.round and robot in self._acted):
            # a retry of an action already applied: the reply it waits for, or the latest
            return await asyncio.shield(waiter) if waiter is not None else self._readings[robot]
        self._actions[robot] = {**(action or {}), "_round": round}
        if waiter is None:
            waiter = self._waiters[robot] = asyncio.get_running_loop().create_future()
        self._pump()
        return await asyncio.shield(waiter)

    def _pump(self) -> None:
        """Apply actions in turn for as long as the robot whose turn it is has sent one."""
        while self.robots:
            todo = [n for n in sorted(self.robots) if n not in self._acted]
            if not todo:  # the round is complete
                if self.world.pheromone is not None:
                    self.world.pheromone.update()
                self.round += 1
                self.world.iteration = self.round
                self._acted.clear()
                self._resolve(self._admit())
                self._over_at_start = self.over()
                if self.on_round is not None:
                    self.on_round(self)
                continue
            name = todo[0]
            self._offer(name)
            action = self._actions.get(name)
            if action is None or action["_round"] != self.round:
                break
            del self._actions[name]
            self._apply(self.robots[name], action)
            self._acted.add(name)
        if not self.robots and self._joins:
            self._resolve(self._admit())
        self._rearm()

    def _offer(self, name: str) -> None:
        """It is ``name``'s turn: its perception is ready; answer its previous action."""
        waiter = self._waiters.get(name)
        pending = self._actions.get(name)
        if (
            waiter is None
            or waiter.done()
            or (pending is not None and pending["_round"] == self.round)
        ):
            return
        bot = self.robots[name]
        self._sense(bot)
        readings = self._readings[name]
        readings["hears"] = self._hears(name)
        readings["over"] = self._over_at_start
        del self._waiters[name]
        waiter.set_result(readings)

    def _rearm(self) -> None:
        """Sequential turns: time the robot whose turn it is, if anyone waits on it."""
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        if any(not w.done() for w in self._waiters.values()):
            self._deadline = asyncio.get_running_loop().call_later(self.timeout, self._expire)

    def _apply(self, bot: _Bot, a: dict[str, Any]) -> None:
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
                if not (self.exclusive and any(b.cell == j for b in self.robots.values())):
                    bot.cell = j
                    bot.moved = True
                    bot.moves += 1

    def _admit(self) -> list[tuple[str, asyncio.Future[dict[str, Any]]]]:
        """Place the robots waiting to join, in name order (not sensed yet)."""
        if not self._started or not self._joins:
            return []
        joins, self._joins = self._joins, {}
        taken = {b.start for b in self.robots.values()}
        free_starts = [s for s in self.starts if s not in taken]
        admitted = []
        for name in sorted(joins):
            spec, future = joins[name]
            try:
                bot = self._place(name, spec, free_starts)
            except ValueError as exc:
                future.set_exception(exc)
                continue
            self.robots[name] = bot
            self._target |= observable(self.cells, [self.grid.cell(bot.start)], bot.view)
            admitted.append((name, future))
        return admitted

    def _resolve(self, admitted: list[tuple[str, asyncio.Future[dict[str, Any]]]]) -> None:
        if admitted:
            self._sense_all()
        for name, future in admitted:
            if not future.done() and name in self.robots:
                future.set_result(
                    {"spec": self._spec_of(self.robots[name]), "readings": self._readings[name]}
                )

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
        if self.exclusive and any(b.cell == start for b in self.robots.values()):
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

    def _expire(self) -> None:
        self._deadline = None
        if self.turns == "sequential":
            todo = [n for n in sorted(self.robots) if n not in self._acted]
            if todo and todo[0] not in self._actions:
                log.warning(
                    "robot %s did not take its turn in round %d within %.1f s: dropped",
                    todo[0],
                    self.round,
                    self.timeout,
                )
                self.dropped.append(todo[0])
                self._remove(todo[0])
            self._pump()
            return
        for name in sorted(set(self.robots) - set(self._actions)):
            log.warning(
                "robot %s sent no action for round %d within %.1f s: dropped",
                name,
                self.round,
                self.timeout,
            )
            self.dropped.append(name)
            self._remove(name)
        self._maybe_step()

    def _remove(self, robot: str) -> None:
        self.robots.pop(robot, None)
        self._acted.discard(robot)
        self._readings.pop(robot, None)
        self._actions.pop(robot, None)
        waiter = self._waiters.pop(robot, None)
        if waiter is not None and not waiter.done():
            waiter.set_exception(RobotDropped(f"robot {robot!r} left the grid world"))
        joining = self._joins.pop(robot, None)
        if joining is not None and not joining[1].done():
            joining[1].cancel()

    # -- perception ---------------------------------------------------------------------------

    def _sense_all(self) -> None:
        for bot in self.robots.values():
            self._sense(bot)
        over = self.over()
        for name in self.robots:
            self._readings[name]["hears"] = self._hears(name)
            self._readings[name]["over"] = over

    def _sense(self, bot: _Bot) -> None:
        w, grid = self.world, self.grid
        ph = w.pheromone.values if w.pheromone is not None else None
        c = bot.cell
        r, col = grid.cell(c)
        occupied = {b.cell for b in self.robots.values() if b is not bot}
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
                self._seen[rr, cc] = True
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
        me = self.robots[name]
        if self.radio is None:
            return sorted(n for n in self.robots if n != name)
        r0, c0 = self.grid.cell(me.cell)
        out = []
        for other, bot in sorted(self.robots.items()):
            if other == name:
                continue
            r, c = self.grid.cell(bot.cell)
            d = (
                abs(r - r0) + abs(c - c0)
                if self.metric == "manhattan"
                else math.hypot(r - r0, c - c0)
            )
            if d <= self.radio:
                out.append(other)
        return out

    # -- snapshots ----------------------------------------------------------------------------

    def snapshot_text(self) -> str:
        """The field as text: ``#`` obstacle, ``B`` base, ``R`` resource, ``@`` robot,
        ``*`` trail (coloured cell), ``+`` seen by a view ray, ``.`` other free cells; then one
        line of the floor values (``-`` unmarked) per row."""
        w, grid = self.world, self.grid
        robots = {b.cell for b in self.robots.values()}
        seen = self._seen.ravel()
        lines = [
            f"round {self.round}  remaining {w.remaining}  delivered {w.delivered}  "
            f"explored {int((self._target & self._seen).sum())}/{int(self._target.sum())}"
        ]
        for r in range(grid.height):
            row = []
            for c in range(grid.width):
                i = r * grid.width + c
                if grid.obstacles[r, c]:
                    ch = "#"
                elif i in robots:
                    ch = "@"
                elif i == w.base:
                    ch = "B"
                elif w.resources[i] > 0:
                    ch = "R"
                elif w.colours[i]:
                    ch = "*"
                elif seen[i]:
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

    def snapshot(self, path: str) -> str:
        """Write the field and trails to ``path`` (PNG if it ends in .png, else text)."""
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        if p.suffix.lower() != ".png":
            p.write_text(self.snapshot_text())
            return str(p)
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        w, grid = self.world, self.grid
        marks = w.marks_array().astype(float)
        marks[grid.obstacles | (marks < 0)] = np.nan
        fig, ax = plt.subplots(figsize=(5, 5))
        ax.imshow(grid.obstacles, cmap="Greys", vmin=0, vmax=1.5)
        ax.imshow(marks, cmap="viridis", alpha=0.8)
        trail = np.argwhere(w.colours_array() != 0)
        if len(trail):
            ax.scatter(trail[:, 1], trail[:, 0], s=12, c="orange", marker="s", label="trail")
        res = np.argwhere(w.resources_array() > 0)
        if len(res):
            ax.scatter(res[:, 1], res[:, 0], s=60, c="green", marker="*", label="resource")
        br, bc = grid.cell(w.base)
        ax.scatter([bc], [br], s=60, c="red", marker="s", label="base")
        pos = np.array([grid.cell(b.cell) for b in self.robots.values()]).reshape(-1, 2)
        if len(pos):
            ax.scatter(pos[:, 1], pos[:, 0], s=30, c="white", edgecolors="black", label="robot")
        ax.set_title(f"round {self.round}, remaining {w.remaining}, delivered {w.delivered}")
        ax.legend(fontsize=6, loc="upper right")
        fig.tight_layout()
        fig.savefig(p, dpi=100)
        plt.close(fig)
        return str(p)

    async def aclose(self) -> None:
        """Fail every pending call."""
        if self._deadline is not None:
            self._deadline.cancel()
        for robot in list(self.robots) + list(self._joins):
            self._remove(robot)


def serve_grid(node: Any, server: GridServer) -> None:
    """Export ``server``'s calls on ``node``: join, step, leave, state, snapshot."""

    async def join(robot: str, spec: dict[str, Any]) -> dict[str, Any]:
        return await server.join(robot, spec or None)

    async def step(robot: str, round: int, action: dict[str, Any]) -> dict[str, Any]:
        return await server.step(robot, round, action)

    async def leave(robot: str) -> None:
        await server.leave(robot)

    def state() -> dict[str, Any]:
        return server.state()

    def snapshot(path: str) -> str:
        return server.snapshot(path)

    for fn in (join, step, leave, state, snapshot):
        node.export(fn, name=fn.__name__)
    # a robot process that dies leaves the team within milliseconds (its liveliness token
    # goes); the lock-step timeout still catches one that hangs
    # on_gone: a member whose link flaps (leaves and joins again within a second) keeps its body
    node.team.on_gone(lambda name: server.drop(name, "left the team"))
