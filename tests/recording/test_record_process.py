"""``mover world --record run.mcap`` as a user runs it: a world process and two robot processes
over zenoh on 127.0.0.1 (the plugin's fixtures), a program launched on them (one leads the
other a metre), the world ended
with Ctrl-C; the file it leaves is read with rosbags, an independent reader."""

from __future__ import annotations

import asyncio
import signal
from pathlib import Path

import pytest

pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")
pytest.importorskip("rosbags", reason="needs rosbags (the test extra)")

from mover import Node, launch
from mover.pytest_plugin import Starter
from mover.testing import Cluster
from tests.recording._rosbags import by_topic

pytestmark = pytest.mark.processes

WORLD = "../../examples/my_program/worlds/two_robots.toml"  # ada and bob
ROBOTS = ("ada", "bob")


async def test_a_world_process_records_poses_commands_and_program_phases(
    mover_world: Starter,
    mover_robots: Starter,
    mover_launcher: Node,
    mover_cluster: Cluster,
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.mcap"
    world = await mover_world(WORLD, "--record", str(path), "--seed", "9", expect=len(ROBOTS))
    await mover_robots(*ROBOTS)
    args = {"trainer": "ada", "places": {"p": [2.0, 1.2]}, "dataset": str(tmp_path / "t.jsonl")}
    outcomes = await launch(mover_launcher, "follow_trainer", list(ROBOTS), args, run="rec1")
    assert all("result" in o for o in outcomes.values()), outcomes
    await asyncio.sleep(1.5)  # the world's next asks of the robots hear their runs' ends
    mover_cluster.kill(world, signal.SIGINT)  # Ctrl-C: the world ends the file
    await asyncio.wait_for(world.wait(), 30)
    got = by_topic(path)
    ticks = len(got["/tf"])
    assert ticks > 1
    for rid in ROBOTS:
        poses = got[f"/{rid}/pose"]
        assert {kind for _, kind, _ in poses} == {"geometry_msgs/msg/PoseStamped"}
        assert len(poses) == len(got[f"/{rid}/cmd_vel"]) == ticks  # both joined before tick 0
        stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, _, m in poses]
        assert stamps == [t for t, _, _ in poses] == sorted(stamps)  # simulated time
        assert {kind for _, kind, _ in got[f"/{rid}/sonar"]} == {"sensor_msgs/msg/LaserScan"}
        heard = got.get(f"/{rid}/phase", [])
        phases = [m.data for _, _, m in heard]
        assert {kind for _, kind, _ in heard} <= {"std_msgs/msg/String"}
        want = "leading" if rid == "ada" else "following"
        # Phases are heard by polling the robots' runs (every 0.5 s) and then their reports: a
        # run this short can be over before the world knows it, so what is recorded is only
        # checked to be the program's, each once (issue 27: the live capture is best effort).
        assert set(phases) <= {want, "done"} and len(phases) == len(set(phases)), phases
    assert [tr.child_frame_id for tr in got["/tf"][-1][2].transforms] == list(ROBOTS)
    # the seed and the world's name are the file's metadata
    from mcap.reader import make_reader

    with path.open("rb") as f:
        meta = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    assert meta["mover"]["seed"] == "9" and meta["mover"]["name"] == "two-robots"
