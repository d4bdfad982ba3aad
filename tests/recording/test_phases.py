"""The world's watch of program phases, on a stand-in node: a run's phase from ``mover.status``
when the run is first seen, then every report on its progress topic, each change once; a robot
that does not answer is asked again later. And the Recorder writes a phase with the next tick,
or as the file closes."""

from __future__ import annotations

import asyncio
import contextlib
import json
from pathlib import Path
from typing import Any

import pytest

from mover import PROGRESS_TOPIC, CallTimeout
from sim_hw import Recorder, World, load_world
from sim_hw.continuous._phases import watch_phases

ROOT = Path(__file__).resolve().parents[2]


class _Sub:
    def __init__(self) -> None:
        self.queue: list[Any] = []
        self.closed = False

    def drain(self) -> list[Any]:
        out, self.queue = self.queue, []
        return out

    def close(self) -> None:
        self.closed = True


class _Message:
    def __init__(self, sender: str, data: Any) -> None:
        self.sender, self.data = sender, data


class _Node:
    def __init__(self) -> None:
        self.status: dict[str, Any] = {}
        self.subs: dict[str, _Sub] = {}
        self.asked: list[str] = []

    async def call(self, member: str, procedure: str, timeout: float = 0.0) -> Any:
        assert procedure == "mover.status"
        self.asked.append(member)
        answer = self.status.get(member)
        if answer is None:
            raise CallTimeout(f"{member} did not answer")
        return answer

    def subscribe(self, topic: str) -> _Sub:
        self.subs[topic] = _Sub()
        return self.subs[topic]


async def test_phases_from_status_then_from_the_runs_reports() -> None:
    node = _Node()
    got: list[tuple[str, str]] = []
    task = asyncio.ensure_future(
        watch_phases(node, lambda: ["a", "b"], lambda m, p: got.append((m, p)))  # type: ignore[arg-type]
    )
    try:
        node.status["a"] = [{"run": "r1", "phase": "searching", "state": "running"}]
        for _ in range(100):
            await asyncio.sleep(0.02)
            if got:
                break
        assert got == [("a", "searching")] and "b" in node.asked  # b did not answer
        sub = node.subs[f"{PROGRESS_TOPIC}/r1"]
        sub.queue += [
            _Message("a", {"member": "a", "phase": "searching"}),  # no change: not again
            _Message("a", {"member": "a", "phase": "found"}),
            _Message("b", {"member": "b", "phase": "gathering"}),
            _Message("b", "not a report"),
        ]
        await asyncio.sleep(0.2)
        assert got == [("a", "searching"), ("a", "found"), ("b", "gathering")]
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
    assert sub.closed


def _phases_recorded(path: Path) -> Any:
    world = World(load_world(ROOT / "worlds" / "search_and_rescue.toml"), seed=1)
    recorder = Recorder(path, world)
    recorder.phase("ernst", "searching")
    recorder({})
    recorder({})
    recorder.phase("ernst", "pushing")  # two after the last tick: both written as it closes
    recorder.phase("ernst", "done")
    recorder.close()
    if path.suffix == ".jsonl":
        return [json.loads(line).get("phases") for line in path.read_text().splitlines()[1:]]
    from rosbags.highlevel import AnyReader

    got: list[tuple[int, str]] = []
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            if conn.topic == "/ernst/phase":
                msg: Any = reader.deserialize(raw, conn.msgtype)
                got.append((t, msg.data))
    return got


def test_the_recorder_writes_phases_with_the_next_tick_into_mcap_only(tmp_path: Path) -> None:
    """Phases reach the world by the wall clock: JSON lines keep none (a seeded run's bytes must
    not depend on the scheduling); MCAP gets each, in order, with the next tick or at the end."""
    assert _phases_recorded(tmp_path / "run.jsonl") == [None, None, None]
    pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")
    pytest.importorskip("rosbags", reason="needs rosbags (the test extra)")
    got = _phases_recorded(tmp_path / "run.mcap")
    assert [p for _, p in got] == ["searching", "pushing", "done"]
