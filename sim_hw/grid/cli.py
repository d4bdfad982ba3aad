"""``mover gridworld FILE``: run a grid world process (the ``gridworld`` verb).

FILE is a grid file (``#``/``.`` text with optional ``B`` base and ``R`` resources, or the
grid JSON of ``sim_hw.grid``) or a maze JSON (``{"grid": ..., "starts": ...}``, as
``sim_hw.grid._maze.save_maze`` writes). A maze is served as the maze papers have it: one robot per
cell, robots placed on the starts in name order, a radio of 25 % of the larger side measured
in Manhattan distance, and a run that is over once everything the robots can see was seen.

``--layout JSON`` overrides or adds: ``base`` [r, c], ``resources`` [[r, c, q], ...],
``place`` {"count": n, "quantity": q} (resources drawn with ``--seed``), ``starts``
[[r, c], ...], ``exclusive``, ``radio`` (cells, or null for everywhere), ``metric``
(manhattan | euclid), ``view`` (ray reach in cells), ``until`` (exhausted | delivered |
explored | never), ``pheromone`` (true, or {"diffusion": d, "evaporation": e}), ``turns``
(together | sequential, as ``--turns``).

The process joins the team of the environment (``MOVER_*``), exports ``join``, ``step``,
``leave``, ``state`` and ``snapshot(path)``, and prints ``READY`` once it serves.
``--record run.mcap`` records the run as MCAP with ROS 2 messages (``sim_hw.grid._mcap``).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mover import NameTaken
from mover.cli import UsageError, json_object
from sim_hw._process import add_world_arguments, count

if TYPE_CHECKING:
    from ._server import GridServer

log = logging.getLogger("sim_hw.grid.cli")


def register(sub: Any) -> None:
    """Add ``gridworld`` to the ``mover`` command's sub-parsers."""
    p = sub.add_parser(
        "gridworld",
        help="run a grid world process (lock-step rounds)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("file", metavar="FILE", help="a grid file (text or JSON) or a maze JSON")
    p.add_argument("--layout", metavar="JSON", help="layout settings as a JSON object")
    add_world_arguments(
        p, name="gridworld", timeout=5.0, tick="round", seed="the world's own draws"
    )
    p.add_argument(
        "--until",
        choices=["exhausted", "delivered", "explored", "never"],
        help="the observer's end of a run (default: by the file)",
    )
    p.add_argument(
        "--turns",
        choices=["together", "sequential"],
        default="together",
        help="together: every robot perceives the round's start (default); "
        "sequential: one at a time in name order, as GridWorld.step",
    )
    p.add_argument("--snapshots", metavar="DIR", help="write text snapshots to DIR")
    p.add_argument(
        "--record",
        metavar="FILE.mcap",
        help="record the run as MCAP with ROS 2 messages (nav_msgs/OccupancyGrid of the cells "
        "and the floor values, the robots' poses), a snapshot every round, or every "
        "--snapshot-every N rounds, and at the end (the mcap extra)",
    )
    p.add_argument(
        "--snapshot-every",
        type=count,
        default=0,
        metavar="N",
        help="a snapshot every N rounds (with --snapshots: 0, only at the end; with --record: "
        "0, every round)",
    )
    p.set_defaults(func=run)


def build_server(
    path: str,
    layout: dict[str, Any],
    *,
    seed: int = 0,
    expect: int = 0,
    timeout: float = 5.0,
    until: str | None = None,
    turns: str = "together",
) -> GridServer:
    """The :class:`~sim_hw.grid._server.GridServer` that FILE and the layout describe."""
    import numpy as np

    from sim_hw.grid import Grid, GridFileError, GridWorld, PheromoneField, load_layout
    from sim_hw.grid import place_resources as place
    from sim_hw.grid._maze import MazeFileError, broadcast_range, load_maze

    from ._server import GridServer

    p = Path(path)
    settings: dict[str, Any] = {}
    try:
        raw = json.loads(p.read_text()) if p.suffix.lower() == ".json" else None
    except (OSError, ValueError) as exc:
        raise UsageError(f"{path}: {exc}") from None
    try:
        if isinstance(raw, dict) and "grid" in raw:
            maze = load_maze(p)
            grid = Grid(maze.grid == 1)
            starts = list(maze.starts)
            base = starts[0] if starts else None
            resources: dict[tuple[int, int], int] = {}
            settings = {
                "exclusive": True,
                "radio": broadcast_range(maze.shape),
                "metric": "manhattan",
                "until": "explored",
            }
        else:
            found = load_layout(p)
            grid, base, resources, starts = found.grid, found.base, dict(found.resources), []
    except (GridFileError, MazeFileError, OSError) as exc:
        raise UsageError(str(exc)) from None
    settings.update(layout)
    cell = _cells(layout)
    if "base" in layout:
        base = cell(layout["base"])
    if base is None:
        free = np.argwhere(~grid.obstacles)
        if not len(free):
            raise UsageError(f"{path}: no free cell")
        centre = np.array(grid.shape) // 2
        r, c = free[np.argmin(np.abs(free - centre).sum(axis=1))]
        base = (int(r), int(c))
    if "resources" in layout:
        resources = {cell(item[:2]): int(item[2]) for item in layout["resources"]}
    if "place" in layout:
        spec = layout["place"]
        home: tuple[int, int] = base
        resources.update(
            place(
                grid,
                int(spec["count"]),
                int(spec["quantity"]),
                seed,
                exclude=(home,),
                reachable_from=home,
            )
        )
    if "starts" in layout:
        starts = [cell(s) for s in layout["starts"]]
    ph = settings.get("pheromone")
    field = None
    if ph:
        ph = ph if isinstance(ph, dict) else {}
        field = PheromoneField(
            ~grid.obstacles, float(ph.get("diffusion", 0.95)), float(ph.get("evaporation", 0.005))
        )
    try:
        world = GridWorld(grid, base, resources, pheromone=field)
        default_until = "exhausted" if resources else "never"
        return GridServer(
            world,
            starts=starts,
            exclusive=bool(settings.get("exclusive", False)),
            radio=settings.get("radio"),
            metric=settings.get("metric", "euclid"),
            until=until or settings.get("until", default_until),
            expect=expect,
            timeout=timeout,
            view=int(settings.get("view", 2)),
            turns=settings.get("turns", turns),
        )
    except ValueError as exc:
        raise UsageError(f"{path}: {exc}") from None


def _cells(layout: dict[str, Any]) -> Any:
    def cell(value: Any) -> tuple[int, int]:
        if not (isinstance(value, list) and len(value) == 2):
            raise UsageError(f"--layout: expected [row, col], got {value!r}")
        return (int(value[0]), int(value[1]))

    return cell


def _write_snapshot(server: GridServer, where: Path) -> None:
    where.mkdir(parents=True, exist_ok=True)
    (where / f"round-{server.round:06d}.txt").write_text(server.snapshot_text())


def run(args: argparse.Namespace) -> int:
    """Run a grid world process until interrupted (or --quit-when-empty)."""
    from mover import NodeConfig, TeamCredentials
    from sim_hw._process import ready_line, run_world_process

    from ._server import serve_grid

    layout = json_object(args.layout, "--layout") if args.layout else {}
    if args.record and Path(args.record).suffix != ".mcap":
        raise UsageError(f"--record: a grid run records as .mcap, got {args.record!r}")
    server = build_server(
        args.file,
        layout,
        seed=args.seed,
        expect=args.expect,
        timeout=args.timeout,
        until=args.until,
        turns=args.turns,
    )
    if args.snapshots and args.snapshot_every > 0:
        every, where = args.snapshot_every, Path(args.snapshots)

        last: list[int] = []

        def on_round(_commands: object) -> None:  # idle rounds change nothing: no snapshot
            if server.round % every == 0:
                w = server.world
                mark = hash(
                    (
                        tuple(w.marks),
                        tuple(w.colours),
                        tuple(w.resources),
                        tuple(sorted(b.cell for b in server.robots.values())),
                    )
                )
                if last != [mark]:
                    last[:] = [mark]
                    _write_snapshot(server, where)

        server.door.on_tick.append(on_round)
    try:
        team, config = TeamCredentials.from_env(), NodeConfig.from_env()
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    recorder = _recorder(args, server)
    try:
        asyncio.run(
            run_world_process(
                server,
                serve_grid,
                name=args.name,
                team=team,
                config=config,
                quit_when_empty=args.quit_when_empty,
                ready=lambda: print(ready_line(args.name, args.file, team, config), flush=True),
            )
        )
    except KeyboardInterrupt:
        return 130
    except NameTaken as exc:
        raise UsageError(str(exc)) from None
    finally:
        if args.snapshots:
            _write_snapshot(server, Path(args.snapshots))
        if recorder is not None:
            recorder.close()
    return 0


def _recorder(args: argparse.Namespace, server: GridServer) -> Any:
    """The MCAP recorder of ``--record``, hooked on the door, or None."""
    if not args.record:
        return None
    from ._mcap import GridMcapSink

    try:
        recorder = GridMcapSink(args.record, server, seed=args.seed, every=args.snapshot_every)
    except OSError as exc:
        raise UsageError(f"cannot write {args.record}: {exc.strerror or exc}") from None
    server.door.on_tick.append(recorder)
    return recorder
