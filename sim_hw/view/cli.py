"""``mover view``: a running world, live in a web browser (the ``view`` verb); and the viewer
half of ``mover replay FILE``.

``mover view [--world NAME] [--port P] [--bind ADDR] [--record FILE.rrd] [--links R]`` starts
rerun's web viewer server (``sim_hw.view._server``) and an observer of the team (from the
environment, like every ``mover`` verb: ``MOVER_TEAM``, the key, ``MOVER_CONNECT``), prints the
page to open, and draws the world until Ctrl-C. Several views may watch one world, each on its
own ``--port``; a port that is taken is a one-line error.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import signal
import sys
import time
from collections.abc import Coroutine
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._server import ViewerServer

from mover.cli import (
    UsageError,
    add_command,
    add_team_arguments,
    bounded,
    member_name,
    positive,
    team_from_args,
)


def add_viewer_arguments(p: argparse.ArgumentParser) -> None:
    """``--port`` and ``--bind``: where the viewer's page is served."""
    p.add_argument(
        "--port",
        type=bounded(int, 1, 65535),
        default=9090,
        help="the viewer page's port (default 9090; one per view)",
    )
    p.add_argument(
        "--bind",
        default="127.0.0.1",
        metavar="ADDR",
        help="the address the viewer listens on (default 127.0.0.1: this machine only)",
    )


def register(sub: Any) -> None:
    """Add ``view`` to the ``mover`` command's sub-parsers."""
    p = add_command(
        sub, "view", run_view, "see a running world live in a web browser (rerun's viewer)"
    )
    p.add_argument(
        "--world",
        type=member_name,
        metavar="NAME",
        help="the world process's name (default: the team's world, whatever its name)",
    )
    add_viewer_arguments(p)
    p.add_argument("--record", metavar="FILE.rrd", help="also save what is shown to a .rrd file")
    p.add_argument(
        "--links",
        type=positive,
        metavar="R",
        help="draw a line between robots within R metres (grid: cells) of each other",
    )
    add_team_arguments(p)


def _say(verb: str) -> Any:
    return lambda line: print(f"mover {verb}: {line}", flush=True)


def run_view(args: argparse.Namespace) -> int:
    """Show a running world in rerun's web viewer, served from this machine: the page to open is
    printed. The view is an observer of the team from the environment (MOVER_TEAM, the key,
    MOVER_CONNECT), not a member; several views may watch one world, each on its own --port.
    Ctrl-C stops it."""
    from ._server import ViewerServer, rerun_binary

    rerun_binary()  # rerun-sdk is there (the view extra), else one line before anything else
    record = Path(args.record) if args.record else None
    if record is not None and (record.suffix != ".rrd" or not record.parent.is_dir()):
        raise UsageError(f"--record must name a .rrd file in an existing folder, got {args.record}")
    team, config = team_from_args(args)
    say = _say("view")
    with ViewerServer(args.port, bind=args.bind) as server:  # first: before any thread starts
        from ._live import LiveView

        view = LiveView(
            world=args.world, grpc_url=server.grpc_url, record=record, links=args.links, say=say
        )
        say(f"open {server.url}")
        try:
            alive = asyncio.run(_watch(view.run(team, config), server))
        except KeyboardInterrupt:
            alive = True
    if not alive:
        print("mover view: the rerun server stopped; exiting", file=sys.stderr)
        return 1
    say("stopped")
    return 0


async def _watch(main: Coroutine[Any, Any, None], server: ViewerServer) -> bool:
    """Run ``main`` until it ends, SIGTERM comes or the server stops; whether it still runs."""
    task = asyncio.ensure_future(main)
    asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, task.cancel)
    while not task.done() and server.alive():
        await asyncio.wait({task}, timeout=1.0)
    if not task.done():
        task.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await task  # its error, if any
    return bool(server.alive())


def replay(path: str, *, port: int, bind: str, rrd: str | None = None) -> int:
    """``mover replay FILE``: the recording in the viewer, on its timeline (or saved to ``rrd``)."""
    from sim_hw.continuous._record import read_recording, run_end

    from ._server import rerun_binary

    rerun_binary()  # rerun-sdk is there, else one line
    header, ticks = read_recording(path)
    header = {"kind": "continuous", **header}  # a grid's MCAP recording says "grid"
    names = {r for t in ticks for r in t.get("robots", {})}
    say = _say("replay")
    if rrd is not None:
        _log_recording(header, ticks, names, grpc_url=None, save=Path(rrd))
        say(f"{rrd}: {len(ticks)} ticks")
        return 0
    from ._server import ViewerServer

    signal.signal(signal.SIGTERM, signal.default_int_handler)
    with ViewerServer(port, bind=bind) as server:
        _log_recording(header, ticks, names, grpc_url=server.grpc_url, save=None)
        say(f"open {server.url}")
        say(
            f"{len(ticks)} ticks, the run ended at {run_end(ticks):.1f} s simulated; Ctrl-C to stop"
        )
        try:
            while server.alive():
                time.sleep(0.5)
        except KeyboardInterrupt:
            say("stopped")
            return 0
    print("mover replay: the rerun server stopped; exiting", file=sys.stderr)
    return 1


def _log_recording(
    header: dict[str, Any],
    ticks: list[dict[str, Any]],
    names: set[str],
    *,
    grpc_url: str | None,
    save: Path | None,
) -> None:
    from ._entities import Drawing, log_frame
    from ._live import close_recording, open_recording

    drawing = Drawing(header, names=names)
    name = str(header.get("name", "recording"))
    rec = open_recording(name, drawing, grpc_url=grpc_url, save=save, live=False)
    try:
        for tick in ticks:
            log_frame(rec, drawing, tick)
    finally:
        close_recording(rec)
