"""The tick frames pinned by real bytes: what a robot and a world process put on the wire.

A change here is a change of the wire between robots and worlds of different versions; the
hex below is what ``mover.pack`` makes of each frame (the node packs a frame as a whole).
"""

from __future__ import annotations

from mover import pack, unpack
from sim_hw._frames import (
    command_frame,
    own_entry,
    read_command,
    read_readings,
    readings_frame,
    topics,
)

COMMAND = bytes.fromhex("93a272310782a176cb3fe0000000000000a177cbbfd0000000000000")
"""``["r1", 7, {"v": 0.5, "w": -0.25}]``"""
READINGS = bytes.fromhex(
    "82a47469636b03a872656164696e677382a161c42082a47469636b03a5736f6e617292cb3ff000000000"
    "0000cb4004000000000000a162c40e82a47469636b03a5736f6e6172c0"
)
"""Tick 3, ``a`` with sonar [1.0, 2.5] and ``b`` with none, each entry packed apart."""


def test_the_topics_of_a_world() -> None:
    assert topics("world") == ("sim/world/commands", "sim/world/readings")


def test_a_command_frame_in_bytes() -> None:
    assert pack(command_frame("r1", 7, {"v": 0.5, "w": -0.25})) == COMMAND
    assert read_command("r1", unpack(COMMAND)) == ("r1", 7, {"v": 0.5, "w": -0.25})


def test_a_command_frame_counts_only_from_its_robot_and_well_formed() -> None:
    assert read_command("mallory", unpack(COMMAND)) is None
    bad: list[object] = [["r1", "7", {}], ["r1", 7, "junk"], ["r1", 7], {"r1": 7}, ["r1", True, {}]]
    assert [read_command("r1", b) for b in bad] == [None] * len(bad)


def test_a_readings_frame_in_bytes() -> None:
    frame = readings_frame(
        3, {"a": {"tick": 3, "sonar": [1.0, 2.5]}, "b": {"tick": 3, "sonar": None}}
    )
    assert pack(frame) == READINGS
    read = read_readings(unpack(READINGS))
    assert read is not None and read.tick == 3 and sorted(read.entries) == ["a", "b"]
    assert own_entry(read, "a") == {"tick": 3, "sonar": [1.0, 2.5]}
    assert own_entry(read, "b") == {"tick": 3, "sonar": None}
    assert own_entry(read, "c") is None


def test_what_is_not_a_readings_frame() -> None:
    bad: list[object] = [["tick", 3], {"tick": 3}, {"tick": "3", "readings": {}}, {"readings": []}]
    assert [read_readings(b) for b in bad] == [None] * len(bad)
    no_tick = read_readings({"readings": {"a": pack(1)}})  # read as never newer than a robot's tick
    assert no_tick is not None and no_tick.tick == -1 and own_entry(no_tick, "a") == 1
