"""Bad command-line inputs get a one-line error and a prompt exit, never a traceback or a hang.

Each case runs the real ``mover`` command (``python -m mover``) against a live team of one
workstation member where a member is needed.
"""

from __future__ import annotations

import asyncio
import os
import sys
import time
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio

from mover.testing import Cluster, cluster

ROOT = Path(__file__).resolve().parents[2]
WORLD = "worlds/search_and_rescue.toml"
BOUND = 15.0  # seconds any bad input may take to be refused


def _files(tmp: Path) -> dict[str, str]:
    files = {
        "huge.toml": '[world]\nname = "huge"\nsize = [1e7, 1e7]\n',
        "count.toml": '[generator]\nkind = "random_obstacles"\ncount = 100000000\n'
        '[world]\nname = "c"\n',
        "rays.toml": '[world]\nname = "r"\nsize = [10, 10]\n'
        "[robot]\nsonar = { rays = 100000000 }\n",
        "deep.json": "[" * 200_000 + "]" * 200_000,
    }
    for name, text in files.items():
        (tmp / name).write_text(text)
    return {name: str(tmp / name) for name in files}


CASES = [
    (["keygen", "--team", "t", "--out", "/nonexistent/dir/key"], {}, "cannot write"),
    (["ps"], {"MOVER_MODE": "bogus"}, "bad zenoh mode"),
    (["ps"], {"MOVER_CONNECT": "garbage"}, "bad zenoh setting"),
    (["call", "r1", "add", "12345678901234567890123456789012"], {}, "cannot"),
    (["call", "r1", "add", "1", "--timeout", "nan"], {}, "--timeout"),
    (["call", "r1", "nope"], {}, "exports no procedure"),
    (["run", "hello_team", "--robots", "r1", "--run-id", "a/b*"], {}, "run"),
    (["robot", "--name", "r9", "--spec", "[1]"], {}, "--spec must be a JSON object"),
    (["robot", "--name", "bad name/*"], {}, "bad robot name"),
    (["world", WORLD, "--name", "a b"], {}, "bad member name"),
    (["world", "{huge.toml}"], {}, "world.size: must be at most"),
    (["world", "{deep.json}"], {}, "nested too deeply"),
    (["world", "{count.toml}"], {}, "generator.count: must be at most"),
    (["world", "{rays.toml}"], {}, "rays: must be at most"),
    (["world", WORLD, "--state-rate", "-1"], {}, "--state-rate"),
    (["router", "--listen", "garbage"], {}, "bad zenoh setting"),
    (["demo", "--timeout", "-1"], {}, "--timeout"),
    (["experiment", "maze", "--size", "0"], {}, "--size must be"),
    (["experiment", "foraging", "--agents", "0"], {}, "--agents must be positive"),
]


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def team() -> AsyncIterator[Cluster]:
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        await c.start("robots", "--name", "r1", "--hardware", "none")
        await node.team.wait_for({"r1"}, timeout=20)
        yield c


@pytest.mark.asyncio(loop_scope="module")
@pytest.mark.parametrize(("args", "env", "said"), CASES, ids=[" ".join(c[0])[:40] for c in CASES])
async def test_a_bad_input_gets_one_line(
    team: Cluster, tmp_path: Path, args: list[str], env: dict[str, str], said: str
) -> None:
    files = _files(tmp_path)
    args = [files[a[1:-1]] if a.startswith("{") else a for a in args]
    environ = {**os.environ, **team.env, **team.team.env(), **team.peer.env(), **env}
    t0 = time.monotonic()
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *args, env=environ, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    out, err = await asyncio.wait_for(proc.communicate(), BOUND)
    took = time.monotonic() - t0
    text = (out + err).decode()
    assert proc.returncode not in (0, None), text
    assert "Traceback" not in text, text
    errors = [
        line for line in err.decode().splitlines() if line.startswith("mover") and said in line
    ]
    assert len(errors) == 1, text  # said once, in one line
    assert took < BOUND
