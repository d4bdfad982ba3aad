"""A run recorded as MCAP with ROS 2 messages reads back, with rosbags (an independent reader)
and with mcap_ros2, as the JSON-lines recording of the same run: topics, types, one message
per robot per recorded tick, stamps in simulated time, equal poses."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")
pytest.importorskip("rosbags", reason="needs rosbags (the test extra)")

from sim_hw.continuous import Recorder, World, load_world, read_recording

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ("r1", "r2")
TICKS = 30


def _run(path: Path) -> None:
    """A short lock-step run: every tick both robots' commands, then the step, then the hook."""
    world = World(load_world(ROOT / "worlds/search_and_rescue.toml"), seed=5)
    for rid in ROBOTS:
        world.add_robot(rid)
    recorder = Recorder(path, world)
    try:
        for k in range(TICKS):
            commands = {
                rid: {"v": 0.2, "w": 0.3 * (i + 1), "led": f"led{k // 10}"}
                for i, rid in enumerate(ROBOTS)
            }
            for rid, cmd in commands.items():
                world.set_command(rid, cmd)
            world.step()
            recorder(commands)
    finally:
        recorder.close()


def _yaw(q: Any) -> float:
    return 2 * math.atan2(q.z, q.w)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("runs")
    _run(folder / "run.jsonl")
    _run(folder / "run.mcap")
    return folder / "run.jsonl", folder / "run.mcap"


def _by_rosbags(path: Path) -> dict[str, list[tuple[int, str, Any]]]:
    from rosbags.highlevel import AnyReader

    got: dict[str, list[tuple[int, str, Any]]] = {}
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            got.setdefault(conn.topic, []).append(
                (t, conn.msgtype, reader.deserialize(raw, conn.msgtype))
            )
    return got


def test_rosbags_reads_the_topics_types_and_poses_of_the_json_lines_run(
    runs: tuple[Path, Path],
) -> None:
    jsonl, mcap = runs
    header, ticks = read_recording(jsonl)
    got = _by_rosbags(mcap)
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
        assert len(poses) == len(ticks) == TICKS + 1  # the start and one a tick
        for (t, _, msg), tick in zip(poses, ticks, strict=True):
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec / 1e9
            assert t == round(tick["t"] * 1e9) and stamp == pytest.approx(tick["t"], abs=1e-9)
            x, y, theta, _led = tick["robots"][rid]
            assert (msg.pose.position.x, msg.pose.position.y) == (x, y)
            assert _yaw(msg.pose.orientation) == pytest.approx(theta, abs=1e-12)
        assert [m[2].data for m in got[f"/{rid}/led"]] == ["", "led0", "led1", "led2"]
        assert got[f"/{rid}/cmd_vel"][-1][2].twist.linear.x == pytest.approx(0.2)
        scan = got[f"/{rid}/sonar"][-1][2]
        assert len(scan.ranges) > 0 and scan.range_max > 0
    assert {m[1] for m in got["/tf"]} == {"tf2_msgs/msg/TFMessage"} and len(got["/tf"]) == TICKS + 1
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
    assert count == TICKS + 1
    # and mover reads it back as it reads the JSON lines, commands aside
    header, ticks = read_recording(jsonl)
    header2, ticks2 = read_recording(mcap)
    assert header2 == header
    for a, b in zip(ticks, ticks2, strict=True):
        assert (a["tick"], a["boxes"]) == (b["tick"], b["boxes"])
        assert a["t"] == pytest.approx(b["t"], abs=1e-9)  # stamps are whole nanoseconds
        for rid in ROBOTS:
            assert (
                a["robots"][rid][:2] == b["robots"][rid][:2]
                and a["robots"][rid][3] == b["robots"][rid][3]
            )


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
    got = _by_rosbags(out)
    _, ticks = read_recording(jsonl)
    assert [m[2].pose.position.x for m in got["/r2/pose"]] == [t["robots"]["r2"][0] for t in ticks]
    assert "/r2/sonar" not in got  # JSON lines keep no sonar
