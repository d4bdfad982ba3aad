"""The tick frames between a world process and its robots: what they say, encoded and decoded
here once (the transports are ``sim_hw._process``, the world's end, and ``sim_hw._link``, the
robot's).

* A **command frame**, broadcast by a robot on the world's command topic:
  ``[robot, tick, command]``. Only its sender may speak for ``robot`` (:func:`read_command`).
* A **readings frame**, broadcast by the world on its readings topic once per tick:
  ``{"tick": n, "readings": {robot: pack(readings)}}``, each robot's entry packed apart so that
  a robot decodes only its own (:func:`read_readings`, :func:`own_entry`).

The node packs each frame as a whole (``mover.pack``); the fixture test of real bytes is
``tests/sim_hw/test_frame_bytes.py``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

from mover import pack, unpack

from ._types import Command, Readings


class CommandFrame(NamedTuple):
    """One robot's command for one tick."""

    robot: str
    tick: int
    command: dict[str, Any]


class ReadingsFrame(NamedTuple):
    """The readings a world sent after tick ``tick``, each robot's still packed."""

    tick: int
    entries: dict[str, bytes]


def topics(world: str) -> tuple[str, str]:
    """The topics of a world's tick frames: (commands to it, readings from it)."""
    return (f"sim/{world}/commands", f"sim/{world}/readings")


def command_frame(robot: str, tick: int, command: Command) -> list[Any]:
    """What a robot broadcasts to hand in ``command`` for ``tick``."""
    return [robot, tick, command]


def read_command(sender: str, data: object) -> CommandFrame | None:
    """The command frame in ``data`` if it is well formed and ``sender`` speaks for itself."""
    if (
        isinstance(data, list)
        and len(data) == 3
        and data[0] == sender
        and type(data[1]) is int
        and isinstance(data[2], dict)
    ):
        return CommandFrame(sender, data[1], data[2])
    return None


def readings_frame(tick: int, readings: Mapping[str, Readings]) -> dict[str, Any]:
    """What a world broadcasts after tick ``tick``: every robot's readings, packed apart."""
    return {"tick": tick, "readings": {r: pack(v) for r, v in readings.items()}}


def read_readings(data: object) -> ReadingsFrame | None:
    """The readings frame in ``data``, or None if it is not one."""
    if not isinstance(data, dict):
        return None
    entries, tick = data.get("readings"), data.get("tick", -1)
    if not isinstance(entries, dict) or type(tick) is not int:
        return None
    return ReadingsFrame(tick, entries)


def own_entry(frame: ReadingsFrame, robot: str) -> Readings | None:
    """``robot``'s readings in ``frame`` (decoded), or None if the frame has none for it."""
    entry = frame.entries.get(robot)
    if isinstance(entry, bytes):
        readings: Readings = unpack(entry)
        return readings
    return None
