"""Aseba Playground, the Thymio's official simulator, as a process: world files and a starter.

``asebaplayground FILE`` (Debian's ``aseba`` package) simulates the robots of a world file in
Enki; each simulated Thymio listens on its own TCP port and speaks Aseba as a physical one does.
:func:`world_xml` writes such a file (metres and radians in, the Playground's centimetres
out); :func:`start_playground` starts it headless (Qt's ``offscreen`` platform: no X server,
no Xvfb) and returns once every robot answers on its port; :func:`stop_playground` ends it.

Without a display the Playground still simulates in real time (about 0.2 of a core for three
robots); it listens on every interface, as it has no option to bind one.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import re
import shutil
import signal
import struct
import sys
import tempfile
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from mover._orphans import guarded
from mover._up._playground import READY, with_ports, world_robots
from robots.hal import HardwareLost

from ._link import Address, AsebaLink

__all__ = [
    "PLAYGROUND",
    "PlaygroundRobot",
    "ground_png",
    "on_ports",
    "playground_command",
    "start_playground",
    "stop_playground",
    "world_xml",
]

# (at the end: ``mover playground``, the world process of a team file's playground world)

PLAYGROUND = "asebaplayground"
"""The simulator's command (Debian package ``aseba``)."""

_STATE_DIRS: dict[int, str] = {}  # the simulated robots' flash, removed as the Playgrounds stop


@dataclass(frozen=True, slots=True)
class PlaygroundRobot:
    """A Thymio in a world file: where it stands (metres, radians) and its TCP port."""

    name: str
    x: float
    y: float
    heading: float
    port: int


def playground_command() -> str | None:
    """The path of ``asebaplayground``, or None when the ``aseba`` package is not installed."""
    return shutil.which(PLAYGROUND)


def world_xml(
    robots: Sequence[PlaygroundRobot],
    *,
    size: tuple[float, float] = (1.0, 1.0),
    walls: Sequence[tuple[float, float, float, float]] = (),
    ground: str | None = None,
) -> str:
    """A Playground world file: an arena of ``size`` metres (walls of the Playground around
    it), ``walls`` as (x, y, length along x, length along y) in metres (centre, 10 cm high),
    ``robots``, and a ``ground`` image (a PNG path relative to the file, stretched over the
    arena; the ground sensors read its brightness)."""

    def cm(v: float) -> str:
        return f"{v * 100:.2f}"

    texture = f' groundTexture="{ground}"' if ground else ""
    lines = [
        "<!DOCTYPE aseba-playground>",
        "<aseba-playground>",
        '  <color name="wall" r="0.9" g="0.9" b="0.9"/>',
        f'  <world w="{cm(size[0])}" h="{cm(size[1])}" color="wall"{texture}/>',
    ]
    lines += [
        f'  <wall x="{cm(x)}" y="{cm(y)}" l1="{cm(lx)}" l2="{cm(ly)}" h="10" color="wall"/>'
        for x, y, lx, ly in walls
    ]
    lines += [
        f'  <robot type="thymio2" x="{cm(r.x)}" y="{cm(r.y)}" angle="{r.heading:.4f}" '
        f'port="{r.port}" name="{r.name}" nodeId="1"/>'
        for r in robots
    ]
    lines.append("</aseba-playground>")
    return "\n".join(lines) + "\n"


def ground_png(
    size: tuple[float, float],
    dark: Sequence[tuple[float, float, float, float]],
    *,
    per_metre: int = 200,
) -> bytes:
    """A grey-scale PNG of a floor of ``size`` metres, white but for the ``dark`` rectangles
    (x0, y0, x1, y1 in metres, y up), to use as a world's ``ground``."""
    w, h = round(size[0] * per_metre), round(size[1] * per_metre)
    rows = []
    for row in range(h):
        y = (h - row - 0.5) / per_metre  # the image's first row is the arena's far side
        line = bytearray(b"\xff" * w)
        for x0, y0, x1, y1 in dark:
            if y0 <= y < y1:
                a, b = max(round(x0 * per_metre), 0), min(round(x1 * per_metre), w)
                line[a:b] = bytes(max(b - a, 0))
        rows.append(b"\x00" + bytes(line))

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    head = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)  # 8-bit grey
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", head)
        + chunk(b"IDAT", zlib.compress(b"".join(rows), 9))
        + chunk(b"IEND", b"")
    )


async def start_playground(
    world: Path,
    ports: Sequence[int],
    *,
    log: IO[bytes] | None = None,
    timeout: float = 20.0,
) -> asyncio.subprocess.Process:
    """Start the Playground on ``world``, headless; return once each robot of ``ports`` answers.

    Its state (the simulated robots' flash) goes to a temporary folder, not the user's. Raises
    FileNotFoundError naming the ``aseba`` package when it is not installed, RuntimeError with
    its last words if it exits or does not listen within ``timeout`` seconds.
    """
    command = playground_command()
    if command is None:
        raise FileNotFoundError(f"{PLAYGROUND} is not installed (Debian package: aseba)")
    state = tempfile.mkdtemp(prefix="mover-playground-")
    env = {
        **os.environ,
        "QT_QPA_PLATFORM": "offscreen",
        "XDG_DATA_HOME": state,
        "XDG_RUNTIME_DIR": state,
    }
    proc = await asyncio.create_subprocess_exec(
        *guarded([command, str(world)]),
        stdin=asyncio.subprocess.DEVNULL,
        stdout=log if log is not None else asyncio.subprocess.DEVNULL,
        stderr=log if log is not None else asyncio.subprocess.DEVNULL,
        env=env,
        cwd=world.parent,
        start_new_session=True,  # a Ctrl-C meant for the robots does not end the world
    )
    _STATE_DIRS[proc.pid] = state
    port = None
    try:
        async with asyncio.timeout(timeout):
            for port in ports:
                await _answering(proc, port)
    except TimeoutError:
        await stop_playground(proc)
        raise RuntimeError(
            f"{PLAYGROUND} {world}: no robot answered on port {port} within {timeout:g} s"
        ) from None
    except BaseException:
        await stop_playground(proc)
        raise
    return proc


async def _answering(proc: asyncio.subprocess.Process, port: int) -> None:
    """Return once the robot on ``port`` answers Aseba (its port listens some time before)."""
    address = Address(host="127.0.0.1", port=port)
    while True:
        if proc.returncode is not None:
            raise RuntimeError(f"{PLAYGROUND} exited with code {proc.returncode}")
        try:
            link = await AsebaLink.open(address, None, 1.0)
        except HardwareLost:
            await asyncio.sleep(0.1)
            continue
        await link.aclose()
        return


async def stop_playground(proc: asyncio.subprocess.Process, sig: int = signal.SIGTERM) -> None:
    """End the Playground (``sig``; SIGKILL after 5 s) and wait for it."""
    if proc.returncode is None:
        with contextlib.suppress(ProcessLookupError):
            proc.send_signal(sig)
        try:
            async with asyncio.timeout(5.0):
                await proc.wait()
        except TimeoutError:
            with contextlib.suppress(ProcessLookupError):
                proc.kill()
            await proc.wait()
    state = _STATE_DIRS.pop(proc.pid, None)
    if state is not None:
        shutil.rmtree(state, ignore_errors=True)


def on_ports(world: Path, ports: Mapping[str, int], folder: Path) -> Path:
    """A copy of ``world`` in ``folder`` with the robots of ``ports`` (by name) on those ports;
    the ground texture it names is linked beside it."""
    text = world.read_text()
    texture = re.search(r'groundTexture="([^"]+)"', text)
    if texture is not None and not Path(texture.group(1)).is_absolute():
        link = folder / texture.group(1)
        link.parent.mkdir(parents=True, exist_ok=True)
        link.symlink_to((world.parent / texture.group(1)).resolve())
    copy = folder / world.name
    copy.write_text(with_ports(text, ports))
    return copy


def register(sub: Any) -> None:
    """Add ``mover playground``: the world process of ``[world] kind = "playground"``."""
    p = sub.add_parser(
        "playground",
        help="run Aseba Playground headless on a world file until Ctrl-C",
        description="Start asebaplayground (Debian package aseba) headless on WORLD, print "
        f"'{READY}: NAME=PORT ...' once every robot answers on its TCP port, and stop it on "
        "Ctrl-C or SIGTERM. What mover up starts for a team file's playground world.",
    )
    p.add_argument("world", metavar="WORLD.playground", help="the world file")
    p.add_argument(
        "--port",
        action="append",
        default=[],
        metavar="NAME=PORT",
        help="run robot NAME on PORT (a temporary copy of the file); repeatable",
    )
    p.add_argument("--timeout", type=float, default=20.0, help="seconds for every robot to answer")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from mover.cli import UsageError

    world = Path(args.world)
    try:
        robots = world_robots(world.read_text(errors="replace"))
    except OSError as exc:
        raise UsageError(f"cannot read {world}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise UsageError(f"{world}: {exc}") from None
    ports: dict[str, int] = {}
    for item in args.port:
        name, _, port = item.partition("=")
        if name not in robots or not port.isdigit() or not 0 < int(port) < 65536:
            raise UsageError(f"--port {item!r}: expected NAME=PORT, NAME a robot of {world}")
        ports[name] = int(port)
    try:
        return asyncio.run(_serve(world, {**robots, **ports}, ports, args.timeout))
    except (FileNotFoundError, RuntimeError) as exc:
        print(f"mover playground: {exc}", file=sys.stderr)
        return 1


async def _serve(world: Path, robots: dict[str, int], moved: dict[str, int], timeout: float) -> int:
    with tempfile.TemporaryDirectory(prefix="mover-world-") as folder:
        file = on_ports(world, moved, Path(folder)) if moved else world
        log = sys.stdout.buffer
        proc = await start_playground(file, list(robots.values()), log=log, timeout=timeout)
        try:
            ready = " ".join(f"{name}={port}" for name, port in robots.items())
            print(f"{READY}: {ready}", flush=True)
            code = await proc.wait()
            print(f"mover playground: {PLAYGROUND} exited with code {code}", file=sys.stderr)
            return 1
        finally:
            await stop_playground(proc)
