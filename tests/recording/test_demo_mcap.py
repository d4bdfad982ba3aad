"""The README's export, on the demo's own recording: ``mover demo`` (search and rescue on
processes), then ``mover replay OUT/world.jsonl --out run.mcap``; the file reads back with
rosbags and mcap_ros2 as the JSON lines it came from, and rerun's importer (what its viewer runs
on a file it opens) turns the poses, the transforms and the LEDs into its own types."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")
pytest.importorskip("rosbags", reason="needs rosbags (the test extra)")

from experiments.demo_runs import run_demo
from sim_hw import read_recording
from tests.recording._rerun import rerun_entities, rerun_program

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    out = tmp_path_factory.mktemp("demo")
    code, text = asyncio.run(run_demo(out))
    assert code == 0, text
    mcap = out / "run.mcap"
    done = subprocess.run(
        [sys.executable, "-m", "mover", "replay", str(out / "world.jsonl"), "--out", str(mcap)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert done.returncode == 0 and done.stdout.strip() == str(mcap), done.stderr
    return out / "world.jsonl", mcap


def _poses(path: Path) -> dict[str, list[tuple[int, float, float]]]:
    from rosbags.highlevel import AnyReader

    got: dict[str, list[tuple[int, float, float]]] = {}
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            if conn.topic.endswith("/pose"):
                assert conn.msgtype == "geometry_msgs/msg/PoseStamped"
                msg: Any = reader.deserialize(raw, conn.msgtype)
                p = msg.pose.position
                got.setdefault(conn.topic, []).append((t, p.x, p.y))
    return got


def test_the_demos_recording_exports_and_reads_back(exported: tuple[Path, Path]) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    jsonl, mcap = exported
    header, ticks = read_recording(jsonl)
    robots = sorted({r for t in ticks for r in t["robots"]})
    assert robots == ["elvis", "ernst", "moseley"]
    poses = _poses(mcap)
    for rid in robots:
        mine = [t for t in ticks if rid in t["robots"]]
        want = [(round(t["t"] * 1e9), *t["robots"][rid][:2]) for t in mine]
        assert poses[f"/{rid}/pose"] == want
    moved = poses["/boxes/victim/pose"]
    assert moved[0][1:] != moved[-1][1:]  # the victim was pushed
    with mcap.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        tf = [m for *_, m in reader.iter_decoded_messages(topics=["/tf"])]
    assert meta["mover"]["seed"] == str(header["seed"])
    assert len(tf) == sum(1 for t in ticks if t["robots"])


@pytest.mark.skipif(rerun_program() is None, reason="needs rerun-sdk (the view extra)")
def test_rerun_opens_it_poses_transforms_and_leds(
    exported: tuple[Path, Path], tmp_path: Path
) -> None:
    jsonl, mcap = exported
    _, ticks = read_recording(jsonl)
    got = rerun_entities(mcap, tmp_path / "run.rrd")
    print({entity: kinds for entity, kinds in got.items() if not entity.startswith("/__")})
    counts: dict[str, Any] = {}
    for rid in ("elvis", "ernst", "moseley"):
        n = sum(1 for t in ticks if rid in t["robots"])
        assert got[f"/{rid}/pose"]["InstancePoses3D"] == n
        assert "TextDocument" in got[f"/{rid}/led"]
        counts[rid] = n
    assert got["/tf"]["Transform3D"] == sum(counts.values())  # one transform per robot a tick
    # kept as ROS 2 messages, not drawn: the arena's markers and the commands
    assert "visualization_msgs.msg.MarkerArray" in got["/arena"]
    assert "geometry_msgs.msg.TwistStamped" in got["/elvis/cmd_vel"]
