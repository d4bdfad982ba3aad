"""The hands-on verbs the docs name, on a real team: `mover topics` and `mover drive ROBOT`.

A lock-step world and one robot process (the plugin's fixtures), and the verbs as a user runs
them: separate processes with the team in their environment. `mover drive` reads its keys from
a pipe (each character a key), so the test drives as a script would. The pure parts (what a key
sends, what a teleop command is, the rate table) are checked without processes first.
"""

from __future__ import annotations

import asyncio
import json
import sys

import pytest

from mover.cli._drive import key_command
from mover.cli._topics import rates
from mover.pytest_plugin import Starter
from mover.testing import Cluster
from programs.teleop import command
from tests.helpers.procs import shell_env

pytestmark = pytest.mark.processes


def test_what_a_key_sends() -> None:
    assert key_command("w", 0.3, 1.0) == [0.3, 0.0]
    assert key_command("\x1b[D", 0.3, 1.0) == [0.0, 1.0]  # the left arrow
    assert key_command("x", 0.3, 1.0) == [0.0, 0.0]
    assert key_command("Q", 0.3, 1.0) == "quit"
    assert key_command("z", 0.3, 1.0) is None


def test_a_teleop_command_is_clipped_and_checked() -> None:
    assert command([2.0, -9.0], 0.5, 1.5) == (0.5, -1.5)
    assert command("quit", 0.5, 1.5) is None
    assert command([True, 0.0], 0.5, 1.5) is None


def test_the_rate_table_is_busiest_first() -> None:
    rows = rates({"a": (2, 200), "b": (10, 1000)}, seconds=2.0)
    assert [(r.topic, r.frames, r.rate, r.mean_bytes) for r in rows] == [
        ("b", 10, 5.0, 100.0),
        ("a", 2, 1.0, 100.0),
    ]


async def _mover(cluster: Cluster, *args: str, keys: bytes = b"") -> tuple[int, str, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *args, env=shell_env(cluster),
        stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    out, err = await asyncio.wait_for(proc.communicate(keys), timeout=90)
    assert proc.returncode is not None
    return proc.returncode, out.decode(), err.decode()


async def test_drive_moves_the_robot_and_topics_hears_it(
    mover_world: Starter, mover_robots: Starter, mover_cluster: Cluster
) -> None:
    await mover_world("../../examples/my_program/worlds/two_robots.toml", expect=1)
    await mover_robots("ada")  # at (1.0, 1.2), heading +x (the world file)
    code, out, err = await _mover(mover_cluster, "topics", "--seconds", "0.5")
    assert code == 0 and "no broadcast heard" in out, out + err  # an idle lock-step world

    async def drive() -> tuple[int, str, str]:
        # the keys arrive at once: the robot drives while they keep coming, then quits
        return await _mover(mover_cluster, "drive", "ada", keys=b"w" * 40 + b"\n" + b"q\n")

    async def topics() -> tuple[int, str, str]:
        await asyncio.sleep(0.5)
        return await _mover(mover_cluster, "topics", "--seconds", "2", "--json")

    (code, out, err), (tcode, tout, terr) = await asyncio.gather(drive(), topics())
    assert code == 0, out + err
    result = json.loads(out.split(": ", 1)[1])
    assert result["moves"] == 40
    assert result["pose"][0] > 1.0 + 0.1, result  # two seconds of keys: it went forward (+x)
    assert tcode == 0, tout + terr
    heard = {row["topic"] for row in map(json.loads, tout.splitlines())}
    assert "sim/world/readings" in heard or "teleop/ada" in heard, tout
