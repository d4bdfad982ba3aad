"""`mover drive ROBOT`: drive one robot from the keyboard.

It joins the team as a member (kind ``tool``), starts the installed program ``teleop`` on the
robot (as ``mover run`` would: nothing is shipped) and sends it a command per key on the
team-wide topic ``teleop/<robot>``: ``[v, w]`` or ``"quit"``. The robot stops by itself when
no key came for the program's ``hold`` (half a second), so holding a key drives and letting go
stops. On a terminal the keys are read one by one (cbreak mode, restored on the way out); from
a pipe, each character of each line is a key, replayed at ``REPEAT`` keys a second as a held
key repeats on a terminal, so a script or a test can drive too.

Keys: ``w``/up forward, ``s``/down back, ``a``/left turn left, ``d``/right turn right, space
or ``x`` stop, ``q`` quit (and Ctrl-C, which also cancels the run). The program's outcome,
the robot's dead-reckoned pose, is printed at the end.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import secrets
import sys
import termios
import tty
from collections.abc import AsyncIterator, Iterator
from typing import TYPE_CHECKING, Any

from .._config import NodeConfig, TeamCredentials
from .._exceptions import CallError, MoverError
from .._programs import PROGRESS_TOPIC, launch, outcomes
from . import add_command, add_team_arguments, bounded, member_name, team_from_args

if TYPE_CHECKING:
    Sub = argparse._SubParsersAction[argparse.ArgumentParser]

__all__ = ["KEYS", "key_command", "register"]

PROGRAM = "teleop"
TOPIC = "teleop"
ARROWS = {"\x1b[A": "w", "\x1b[B": "s", "\x1b[D": "a", "\x1b[C": "d"}
KEYS = {"w": (1.0, 0.0), "s": (-1.0, 0.0), "a": (0.0, 1.0), "d": (0.0, -1.0), " ": (0.0, 0.0)}
"""Each key's command as fractions of (speed, turn rate); ``x`` is space (stop)."""
READY_TIMEOUT = 10.0  # seconds for the program to say it listens (it reports "driving")
REPEAT = 20.0  # keys per second read from a pipe (a terminal's key repeat is 20-30)
HELP = "w/up forward, s/down back, a/left and d/right turn, space or x stop, q quit"


def key_command(key: str, speed: float, turn: float) -> list[float] | str | None:
    """What one key sends: ``[v, w]``, ``"quit"``, or None for a key that means nothing."""
    key = ARROWS.get(key, key.lower())
    if key == "q":
        return "quit"
    fraction = KEYS.get(" " if key == "x" else key)
    return None if fraction is None else [fraction[0] * speed, fraction[1] * turn]


def register(sub: Sub) -> None:
    """Add ``mover drive``."""
    p = add_command(
        sub,
        "drive",
        run_drive,
        "drive a robot from the keyboard",
        "Start the `teleop` program on ROBOT and drive it with the keys: "
        + HELP
        + ". Holding a key drives; the robot stops half a second after the last key. Read"
        " from a pipe, each character of each line is a key, 20 a second. Not while the robot is in"
        " another run (it refuses).",
    )
    p.add_argument("robot", type=member_name, help="the robot to drive")
    p.add_argument(
        "--speed",
        type=bounded(float, 0.0, 10.0, above=True),
        default=0.3,
        help="forward speed in m/s (default 0.3; the drive clips it)",
    )
    p.add_argument(
        "--turn",
        type=bounded(float, 0.0, 10.0, above=True),
        default=1.0,
        help="turn rate in rad/s (default 1)",
    )
    add_team_arguments(p)


def run_drive(args: argparse.Namespace) -> int:
    """Drive until ``q``, the end of the keys, or Ctrl-C."""
    team, config = team_from_args(args)
    return asyncio.run(_drive(team, config, args.robot, args.speed, args.turn))


async def _drive(
    team: TeamCredentials, config: NodeConfig, robot: str, speed: float, turn: float
) -> int:
    from .._node import Node

    run = f"drive-{robot}-{secrets.token_hex(2)}"
    async with Node(f"drive-{secrets.token_hex(3)}", team, kind="tool", config=config) as node:
        try:
            await node.membership.wait_for([robot], timeout=5.0)
        except TimeoutError:
            print(f"mover drive: {robot!r} is not in team {team.name!r}", file=sys.stderr)
            return 1
        progress = node.subscribe(f"{PROGRESS_TOPIC}/{run}")
        try:
            await launch(node, PROGRAM, [robot], {"topic": TOPIC}, run=run, wait=False)
            async with asyncio.timeout(READY_TIMEOUT):  # keys sent before it listens are lost
                async for report in progress:
                    if isinstance(report.data, dict) and report.data.get("phase") == "driving":
                        break
        except CallError as exc:
            print(f"mover drive: {robot} did not start {PROGRAM}: {exc}", file=sys.stderr)
            return 1
        except TimeoutError:
            print(f"mover drive: {PROGRAM} on {robot} did not start listening", file=sys.stderr)
            await node.call(robot, "mover.cancel", run, timeout=5.0)
            return 1
        finally:
            progress.close()
        print(f"mover drive: driving {robot} ({HELP})", file=sys.stderr)
        ended = False
        try:
            async for key in _keys():
                sent = key_command(key, speed, turn)
                if sent is not None:
                    await node.broadcast(f"{TOPIC}/{robot}", sent, reliable=True)
                if sent == "quit":
                    break
            else:
                await node.broadcast(f"{TOPIC}/{robot}", "quit", reliable=True)
            ended = True
            outcome = (await outcomes(node, run, [robot]))[robot]
        finally:
            if not ended:  # Ctrl-C: the run must not go on without its driver
                with contextlib.suppress(MoverError):
                    await node.call(robot, "mover.cancel", run, timeout=5.0)
    return _print_outcome(robot, outcome)


def _print_outcome(robot: str, outcome: dict[str, Any]) -> int:
    if "error" in outcome:
        print(f"mover drive: {robot}: {outcome['error']}", file=sys.stderr)
        return 1
    print(f"{robot}: {json.dumps(outcome.get('result'))}")
    return 0


async def _keys() -> AsyncIterator[str]:
    """Keys from standard input: one by one on a terminal, else the characters of each line
    at ``REPEAT`` a second."""
    loop = asyncio.get_running_loop()
    fd = sys.stdin.fileno()
    piped = not os.isatty(fd)
    queue: asyncio.Queue[str] = asyncio.Queue()

    def readable() -> None:
        data = os.read(fd, 64).decode(errors="replace")
        queue.put_nowait(data)  # "" at the end of the input

    with _cbreak(fd):
        loop.add_reader(fd, readable)
        try:
            while chunk := await queue.get():
                for key in _split(chunk):
                    yield key
                    if piped:
                        await asyncio.sleep(1.0 / REPEAT)
        finally:
            loop.remove_reader(fd)


def _split(chunk: str) -> Iterator[str]:
    i = 0
    while i < len(chunk):
        if chunk.startswith("\x1b[", i) and i + 2 < len(chunk):
            yield chunk[i : i + 3]
            i += 3
        else:
            if chunk[i] != "\n":
                yield chunk[i]
            i += 1


@contextlib.contextmanager
def _cbreak(fd: int) -> Iterator[None]:
    if not os.isatty(fd):
        yield
        return
    saved = termios.tcgetattr(fd)
    tty.setcbreak(fd)
    try:
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)
