"""A run recorded as MCAP with ROS 2 messages reads back, with rosbags (an independent reader)
and with mcap_ros2, as the JSON-lines recording of the same run: topics, types, one message
per robot per recorded tick, stamps in simulated time, equal poses."""

from __future__ import annotations

import asyncio
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")
pytest.importorskip("rosbags", reason="needs rosbags (the test extra)")

from sim_hw import Recorder, World, WorldServer, in_process, load_world, read_recording
from sim_hw.continuous._walker import random_walk
from tests.recording._rosbags import by_topic

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ("r1", "r2")
TICKS = 30


async def _run(path: Path) -> None:
    """A short lock-step run of two random walkers, in-process, recorded by the door's hook."""
    world = World(load_world(ROOT / "worlds/search_and_rescue.toml"), seed=5)
    recorder = Recorder(path, world)
    server = WorldServer(world, lockstep=True, expect=len(ROBOTS))
    server.door.on_tick.append(recorder)

    async def robot(rid: str, seed: int) -> None:
        hw = await in_process(server, rid)
        await random_walk(hw, np.random.default_rng(seed), TICKS)

    try:
        await asyncio.gather(*(robot(rid, k) for k, rid in enumerate(ROBOTS)))
        await server.door.aclose()
    finally:
        recorder.close()


def _yaw(q: Any) -> float:
    return 2 * math.atan2(q.z, q.w)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("runs")
    asyncio.run(_run(folder / "run.jsonl"))
    asyncio.run(_run(folder / "run.mcap"))
    return folder / "run.jsonl", folder / "run.mcap"


def test_rosbags_reads_the_topics_types_and_poses_of_the_json_lines_run(
    runs: tuple[Path, Path],
) -> None:
    jsonl, mcap = runs
    header, ticks = read_recording(jsonl)
    got = by_topic(mcap)
    for rid in ROBOTS:
        types = {
            f"/{rid}/pose": "geometry_msgs/msg/PoseStamped",
            f"/{rid}/odom_pose": "geometry_msgs/msg/PoseStamped",
            f"/{rid}/cmd_vel": "geometry_msgs/msg/TwistStamped",
            f"/{rid}/sonar": "sensor_msgs/msg/LaserScan",
            f"/{rid}/led": "std_msgs/msg/String",
        }
        for topic, kind in types.items():
            assert {m[1] for m in got[topic]} == {kind}, topic
        poses = got[f"/{rid}/pose"]
        mine = [tick for tick in ticks if rid in tick["robots"]]  # from its join on
        assert len(poses) == len(mine) >= TICKS  # one a recorded tick
        for (t, _, msg), tick in zip(poses, mine, strict=True):
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec / 1e9
            assert t == round(tick["t"] * 1e9) and stamp == pytest.approx(tick["t"], abs=1e-9)
            x, y, theta, _led = tick["robots"][rid]
            assert (msg.pose.position.x, msg.pose.position.y) == (x, y)
            assert _yaw(msg.pose.orientation) == pytest.approx(theta, abs=1e-12)
        leds = [tick["robots"][rid][3] for tick in mine]
        changes = [led for k, led in enumerate(leds) if k == 0 or led != leds[k - 1]]
        assert [m[2].data for m in got[f"/{rid}/led"]] == changes
        assert len(got[f"/{rid}/cmd_vel"]) == len(mine)
        scan = got[f"/{rid}/sonar"][-1][2]
        assert len(scan.ranges) > 0 and scan.range_max > 0
    assert {m[1] for m in got["/tf"]} == {"tf2_msgs/msg/TFMessage"} and len(got["/tf"]) == sum(
        1 for tick in ticks if tick["robots"]
    )
    assert [tr.child_frame_id for tr in got["/tf"][-1][2].transforms] == list(ROBOTS)
    arena = got["/arena"]
    assert len(arena) == 1 and arena[0][1] == "visualization_msgs/msg/MarkerArray"
    assert len(arena[0][2].markers) == 1 + len(header["obstacles"]) + len(header["immovables"])


def test_mcap_ros2_reads_it_and_the_metadata_holds_the_seed(runs: tuple[Path, Path]) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    jsonl, mcap = runs
    with mcap.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        count = sum(1 for _, ch, _, _ in reader.iter_decoded_messages(topics=["/r1/pose"]))
    assert meta["mover"]["seed"] == "5" and meta["mover"]["name"]
    assert count == sum(1 for tick in read_recording(jsonl)[1] if "r1" in tick["robots"])
    # and mover reads it back as it reads the JSON lines, commands aside
    header, ticks = read_recording(jsonl)
    header2, ticks2 = read_recording(mcap)
    assert header2 == header
    for a, b in zip(ticks, ticks2, strict=True):
        assert (a["tick"], a["boxes"]) == (b["tick"], b["boxes"])
        assert a["t"] == pytest.approx(b["t"], abs=1e-9)  # stamps are whole nanoseconds
        assert set(a["robots"]) == set(b["robots"])
        for rid, pose in a["robots"].items():
            assert b["robots"][rid] == [*pose[:2], pytest.approx(pose[2], abs=1e-12), pose[3]]


@pytest.mark.processes
def test_replay_exports_a_json_lines_recording_as_mcap(
    runs: tuple[Path, Path], tmp_path: Path
) -> None:
    jsonl, _ = runs
    out = tmp_path / "export.mcap"
    done = subprocess.run(
        [sys.executable, "-m", "mover", "replay", str(jsonl), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(out)
    got = by_topic(out)
    _, ticks = read_recording(jsonl)
    assert [m[2].pose.position.x for m in got["/r2/pose"]] == [
        t["robots"]["r2"][0] for t in ticks if "r2" in t["robots"]
    ]
    assert "/r2/sonar" not in got  # JSON lines keep no sonar
