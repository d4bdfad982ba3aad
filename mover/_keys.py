"""Every zenoh key expression mover uses, built in one place.

``mover/<team>/rpc/<robot>``     a robot's procedure calls (queryable)
``mover/<team>/ctl/<robot>``     control messages to a robot, e.g. cancelling a call
``mover/<team>/hello/<robot>``   authenticated member information (queryable)
``mover/<team>/alive/<robot>``   a member's liveliness token
``mover/<team>/bc/<topic>``      team broadcasts (team-wide, or range-limited when not in a cell)
``mover/<team>/bcc/<level>/<ix>_<iy>/<topic>``  range-limited broadcasts sent from one cell of
                                 the grid of level ``level`` (cells of 2**level metres)
``mover/<team>/bcl/<level>/<robot>/<topic>``    a sender's liveliness token: it sends ``topic``
                                 into cells of that level
"""

from __future__ import annotations

import re

_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]{0,63}$")
_TOPIC = re.compile(r"^[A-Za-z0-9_.\-]+(/[A-Za-z0-9_.\-]+)*$")
ROOT = "mover"


def check_name(what: str, name: str) -> str:
    """Return ``name`` if it is a valid team or robot name, else raise ValueError."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(
            f"bad {what} name {name!r}: use 1-64 letters, digits, '_', '-', '.', "
            "starting with a letter, digit or '_'"
        )
    return name


def check_topic(topic: str) -> str:
    """Return ``topic`` if it is a valid broadcast topic ('/'-separated names), else raise."""
    if not isinstance(topic, str) or not _TOPIC.match(topic):
        raise ValueError(f"bad topic {topic!r}: use '/'-separated names, no wildcards")
    return topic


def rpc(team: str, robot: str) -> str:
    return f"{ROOT}/{team}/rpc/{robot}"


def ctl(team: str, robot: str) -> str:
    return f"{ROOT}/{team}/ctl/{robot}"


def hello(team: str, robot: str) -> str:
    return f"{ROOT}/{team}/hello/{robot}"


def alive(team: str, robot: str) -> str:
    return f"{ROOT}/{team}/alive/{robot}"


def broadcast(team: str, topic: str) -> str:
    return f"{ROOT}/{team}/bc/{topic}"


def broadcast_cell(team: str, level: int | str, cell: str, topic: str) -> str:
    return f"{ROOT}/{team}/bcc/{level}/{cell}/{topic}"


def broadcast_level(team: str, level: int | str, robot: str, topic: str) -> str:
    return f"{ROOT}/{team}/bcl/{level}/{robot}/{topic}"


def level_of(key: str) -> int:
    """The level in a ``bcl`` key."""
    return int(key.split("/")[3])


def robot_of(key: str) -> str:
    """The robot name at the end of a per-robot key."""
    return key.rsplit("/", 1)[-1]
