"""An MCAP recording as rosbags (an independent reader) reads it: every message, decoded, by
topic, so that the recording tests check the files with a reader that is not ours."""

from __future__ import annotations

from pathlib import Path
from typing import Any

Message = tuple[int, str, Any]
"""A message: its stamp (ns), its ROS 2 type, its decoded body."""


def by_topic(path: Path) -> dict[str, list[Message]]:
    """Every message of the MCAP file at ``path``, by topic, in the file's order."""
    from rosbags.highlevel import AnyReader

    got: dict[str, list[Message]] = {}
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            got.setdefault(conn.topic, []).append(
                (t, conn.msgtype, reader.deserialize(raw, conn.msgtype))
            )
    return got
