"""The ``mover world`` and ``mover replay`` verbs (entry points of the ``mover`` command).

``mover world WORLDFILE [--lockstep [--control-delay K]] [--speed X] [--seed N] [--record FILE]``
runs the world process: it joins the team from the environment (``MOVER_*``), exports
``join``/``step``/``leave`` and streams snapshots on ``world/state``. ``mover replay FILE``
plays a recording in the web viewer (``sim_hw.view``); ``mover replay FILE --out PNG`` draws it.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mover import NameTaken
from mover.cli import UsageError, add_command, positive
from sim_hw._process import add_world_arguments, control_delay, rate, ready_line

if TYPE_CHECKING:
    from mover import Node

    from ._record import Recorder
    from ._stepper import WorldServer

log = logging.getLogger("sim_hw.continuous.cli")


def register_world(sub: Any) -> None:
    """Add ``world`` to the ``mover`` command's sub-parsers."""
    p = add_command(sub, "world", run_world, "run a simulated world process")
    p.add_argument("worldfile", metavar="WORLDFILE", help="a .toml or .json world file")
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="advance only when every robot has sent its command for the tick",
    )
    p.add_argument(
        "--speed",
        type=positive,
        default=1.0,
        help="real-time mode: simulated seconds per wall second (default 1)",
    )
    p.add_argument(
        "--record",
        metavar="FILE",
        help="record the run: as MCAP with ROS 2 messages if FILE ends in .mcap (the mcap "
        "extra), else as JSON lines",
    )
    p.add_argument("--until", type=positive, metavar="T", help="stop at simulated time T")
    p.add_argument(
        "--state-rate",
        type=rate,
        default=2.0,
        metavar="HZ",
        help="snapshots per simulated second on world/state (0: none)",
    )
    p.add_argument(
        "--control-delay",
        type=control_delay,
        default=os.environ.get("MOVER_CONTROL_DELAY", "0"),
        metavar="K",
        help="lock-step: a command handed in for tick t applies at tick t + K, so that the "
        "world runs up to K ticks ahead of the network's round trip (default "
        "$MOVER_CONTROL_DELAY, else 0)",
    )
    add_world_arguments(p, name="world", timeout=2.0, tick="tick", seed="the sensor noise")


def run_world(args: argparse.Namespace) -> int:
    """Run a world process until interrupted (or --until, --quit-when-empty)."""
    from mover import NodeConfig, TeamCredentials
    from sim_hw._process import run_world_process

    from . import Recorder, WorldFileError, WorldServer, load_world, serve_world
    from ._contract import TICK
    from ._world import World

    try:
        spec = load_world(args.worldfile)
    except WorldFileError as exc:
        raise UsageError(str(exc)) from None
    try:
        team, config = TeamCredentials.from_env(), NodeConfig.from_env()
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    world = World(spec, seed=args.seed)
    recorder = None
    if args.record:
        try:
            recorder = Recorder(args.record, world)
        except OSError as exc:
            raise UsageError(f"cannot write {args.record}: {exc.strerror or exc}") from None
    every = round(1.0 / (args.state_rate * TICK)) if args.state_rate > 0 else 0
    server = WorldServer(
        world,
        lockstep=args.lockstep,
        speed=args.speed,
        expect=args.expect,
        timeout=args.timeout,
        snapshot_every=max(every, 1) if every else 0,
        control_delay=args.control_delay if args.lockstep else 0,
    )
    if recorder is not None:
        server.door.on_tick.append(recorder)
    try:
        asyncio.run(
            run_world_process(
                server,
                serve_world if recorder is None else _recording(recorder),
                name=args.name,
                until_tick=None if args.until is None else math.ceil(round(args.until / TICK, 9)),
                quit_when_empty=args.quit_when_empty,
                team=team,
                config=config,
                ready=lambda: print(
                    ready_line(args.name, args.worldfile, team, config), flush=True
                ),
            )
        )
    except NameTaken as exc:
        raise UsageError(str(exc)) from None
    finally:
        if recorder is not None:
            recorder.close()
    return 0


def _recording(recorder: Recorder) -> Callable[[Node, WorldServer], None]:
    """``serve_world``, plus a watch of the robots' program phases for ``recorder``."""
    from . import serve_world
    from ._phases import watch_phases

    def export(node: Node, server: WorldServer) -> None:
        serve_world(node, server)
        task = asyncio.ensure_future(watch_phases(node, server.door.stepper.robots, recorder.phase))
        _KEEP.append(task)

    return export


_KEEP: list[asyncio.Future[None]] = []  # the phase watch runs as long as the world's loop


def register_replay(sub: Any) -> None:
    """Add ``replay`` to the ``mover`` command's sub-parsers."""
    from sim_hw.view.cli import add_viewer_arguments

    p = add_command(
        sub, "replay", run_replay, "play a recorded run in the web viewer, or draw it to a PNG"
    )
    p.add_argument("file", metavar="FILE", help="a recording made with mover world --record")
    p.add_argument(
        "--out",
        metavar="PNG|RRD|MCAP",
        help="write the trajectories to a .png, the replay to a .rrd file, or the recording "
        "as MCAP with ROS 2 messages (.mcap), instead of showing it",
    )
    add_viewer_arguments(p)


def run_replay(args: argparse.Namespace) -> int:
    """Play a recording in the web viewer on its timeline (pause, scrub, speed); with --out, draw
    the arena and the trajectories to a PNG, or save the replay as a .rrd file."""
    from ._record import plot_recording

    if not Path(args.file).is_file():
        raise UsageError(f"{args.file}: no such file")
    out = None if args.out is None else str(args.out)
    if out is not None and not out.endswith((".png", ".rrd", ".mcap")):
        raise UsageError(f"--out must name a .png, .rrd or .mcap file, got {args.out!r}")
    try:
        if out is not None and out.endswith(".mcap"):
            from ._mcap import export

            export(args.file, out)
        elif out is None or out.endswith(".rrd"):
            from sim_hw.view.cli import replay

            return replay(args.file, port=args.port, bind=args.bind, rrd=out)
        else:
            if Path(args.file).suffix == ".mcap":
                from ._mcap import recording_kind

                if recording_kind(args.file) == "grid":
                    raise UsageError(f"{args.file}: a grid recording plays in the viewer only")
            plot_recording(args.file, out)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:
        raise UsageError(f"cannot write {out}: {exc.strerror or exc}") from None
    print(out)
    return 0
