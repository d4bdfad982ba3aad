"""Bad command-line inputs get a one-line error and a prompt exit, never a traceback or a hang.

Each case runs the real ``mover`` command (``python -m mover``) against a live team of one
workstation member where a member is needed: the cases of issue 12 ("34 of 189 bad CLI inputs"),
then unknown and malformed options, negative, NaN, infinite and huge numbers, files that are
missing, directories, not UTF-8, endless (/dev/zero) or nested too deeply, and bad settings in
the environment. A case that still fails is a strict xfail naming the file and line to fix.
"""

from __future__ import annotations

import asyncio
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio

from mover.testing import Cluster, cluster

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]
WORLD = "worlds/search_and_rescue.toml"
BOUND = 15.0  # seconds any bad input may take to be refused
HANGS = 5.0  # the bound of a case known to hang (xfail): a hang costs the suite no more


def _files(tmp: Path) -> dict[str, str]:
    files: dict[str, str | bytes] = {
        "huge.toml": '[world]\nname = "huge"\nsize = [1e7, 1e7]\n',
        "count.toml": '[generator]\nkind = "random_obstacles"\ncount = 100000000\n'
        '[world]\nname = "c"\n',
        "rays.toml": '[world]\nname = "r"\nsize = [10, 10]\n'
        "[robot]\nsonar = { rays = 100000000 }\n",
        "deep.json": "[" * 200_000 + "]" * 200_000,
        "badid.toml": '[world]\nname = "w"\nsize = [10, 10]\n[[robots]]\nid = "bad name/*"\n',
        "grid.txt": "....\n....\n..B.\n....\n",
        "latin1.toml": b'[world]\nname = "caf\xe9"\n',
        "latin1.json": b'{"world": {"name": "caf\xe9"}}',
        "latin1.txt": b"..\xe9.\n....\n",
        "teamnum.toml": "robots = 5\n",
        "existing": "a file where a directory is wanted\n",
        "finecell.toml": '[world]\nname = "f"\nsize = [10, 10]\ncell = 1e-6\n',
    }
    for name, text in files.items():
        path = tmp / name
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text)
    (tmp / "adir").mkdir(exist_ok=True)
    return {name: str(tmp / name) for name in [*files, "adir"]}


def case(
    args: list[str],
    said: str,
    env: dict[str, str | None] | None = None,
    *,
    fails: str | None = None,
    bound: float = BOUND,
) -> Any:
    """One bad input: ``mover ARGS`` (``{name}`` stands for a file of ``_files``) must say
    ``said`` in one line; ``fails``: why it does not yet (a strict xfail naming the place)."""
    marks = [pytest.mark.xfail(strict=True, reason=fails)] if fails else []
    ident = " ".join(args)[:56] + (
        " " + ",".join(f"{k}={v}" for k, v in env.items()) if env else ""
    )
    while ident in _IDS:
        ident += "'"
    _IDS.add(ident)
    return pytest.param(args, env or {}, said, bound, marks=marks, id=ident)


_IDS: set[str] = set()


KEYLESS: dict[str, str | None] = {"MOVER_TEAM_KEY": None}
CASES = [
    # the list ("34 of 189 bad CLI inputs")
    case(["keygen", "--team", "t", "--out", "/nonexistent/dir/key"], "cannot write"),
    case(["ps"], "bad zenoh mode", {"MOVER_MODE": "bogus"}),
    case(["ps"], "bad zenoh setting", {"MOVER_CONNECT": "garbage"}),
    case(["call", "r1", "add", "12345678901234567890123456789012"], "cannot"),
    case(["call", "r1", "add", "1", "--timeout", "nan"], "--timeout"),
    case(["call", "r1", "nope"], "exports no procedure"),
    case(["run", "hello_team", "--robots", "r1", "--run-id", "a/b*"], "run"),
    case(["robot", "--name", "r9", "--spec", "[1]"], "--spec must be a JSON object"),
    case(["robot", "--name", "bad name/*"], "bad robot name"),
    case(["world", WORLD, "--name", "a b"], "bad member name"),
    case(
        ["world", "{huge.toml}"],
        "huge.toml:3: world.size: must be a list of 2 numbers, each > 0 and at most 1000",
    ),
    case(["world", "{deep.json}"], "nested too deeply"),
    case(["world", "{count.toml}"], "generator.count: must be from 0 to 10000, got 100000000"),
    case(["world", "{rays.toml}"], "robot.sonar.rays: must be from 1 to 360, got 100000000"),
    case(["world", WORLD, "--state-rate", "-1"], "--state-rate"),
    case(["router", "--listen", "garbage"], "--listen 'garbage': not an endpoint"),
    case(["demo", "--timeout", "0.5"], "no result within 0.5 s"),
    case(["demo", "--timeout", "-1"], "--timeout"),
    case(["experiment", "maze", "--size", "0"], "--size must be"),
    case(["experiment", "foraging", "--agents", "0"], "--agents must be positive"),
    case(
        ["world", "{badid.toml}"],
        "bad name/*",
    ),
    # the last four (issue 24): found before any work starts
    case(["world", "{finecell.toml}"], "world.cell: 1e-06 m makes 1e+14 floor cells, over"),
    case(["router", "--listen", "tcp/127.0.0.1:99999"], "the port must be from 0 to 65535"),
    case(["demo", "--program", "nosuch"], "--program 'nosuch' is not installed (installed: "),
    case(["experiment", "maze", "--out", "/proc/x"], "--out /proc/x: cannot write in /proc"),
    case(["experiment", "foraging", "--out", "{existing}/x"], "{existing} is not a directory"),
    case(["experiment", "levy", "--save", "/proc/x"], "--save /proc/x: cannot write in /proc"),
    case(["experiment", "eyebot", "--out", "/proc/x"], "--out /proc/x: cannot write in /proc"),
    case(["demo", "--out", "/proc/x"], "--out /proc/x: cannot write in /proc"),
    case(["router", "--listen", "tcp/[::1:7447"], "in brackets"),
    case(["router", "--listen", "bogus/127.0.0.1:7447"], "unknown protocol 'bogus'"),
    # options: unknown, malformed, negative, NaN, infinite, huge
    case(["call", "r1", "add", "--bogus-option"], "unrecognized arguments: --bogus-option"),
    case(["bogusverb"], "invalid choice: 'bogusverb'"),
    case(["--log-level", "loud", "ps"], "unknown log level 'loud'"),
    case(["call", "r1", "add", "1", "--timeout", "inf"], "--timeout"),
    case(["call", "r1", "add", "1", "--timeout", "-1"], "--timeout"),
    case(["call", "r1", "add", "--kwargs", '{"x":'], "--kwargs is not JSON"),
    case(["run", "hello_team", "--args", "[1]"], "--args must be a JSON object"),
    case(["world", WORLD, "--speed", "nan"], "--speed"),
    case(["world", WORLD, "--speed", "-1"], "--speed"),
    case(["world", WORLD, "--until", "inf"], "--until"),
    case(["world", WORLD, "--state-rate", "nan"], "--state-rate"),
    case(["world", WORLD, "--lockstep", "--expect", "-1"], "--expect"),
    case(["world", WORLD, "--lockstep", "--timeout", "nan"], "--timeout"),
    case(["world", WORLD, "--seed", "1.5"], "--seed"),
    case(["gridworld", "{grid.txt}", "--expect", "-1"], "--expect"),
    case(["gridworld", "{grid.txt}", "--timeout", "nan"], "--timeout"),
    case(["demo", "--timeout", "nan"], "--timeout"),
    case(["demo", "--seed", "-1"], "--seed must be from 0"),
    case(["demo", "--args", "[1]"], "--args must be a JSON object"),
    case(["experiment", "maze", "--size", "100000000"], "--size must be from 4 to 1000"),
    case(["experiment", "maze", "--runs", "-1"], "--runs must be from 1 to 100000, got -1"),
    case(["experiment", "foraging", "--runs", "-1"], "--runs must be from 1"),
    case(["experiment", "foraging", "--max-iterations", "-1"], "--max-iterations must be"),
    case(["experiment", "levy", "--alpha", "nan"], "--alpha and --alphas must be in"),
    case(["experiment", "levy", "--workers", "0"], "--workers must be from 1 to 64, got 0"),
    case(["experiment", "levy", "--max-time", "-1"], "must be positive"),
    case(["robot", "--name", "r9", "--option", "garbage"], "expected KEY=VALUE"),
    case(["robot", "--name", "r9", "--hardware", "bogus"], "no hardware backend 'bogus'"),
    case(["keygen", "--team", "a b"], "bad team name"),
    case(["ps", "--wait", "nan"], "--wait"),
    case(["ps", "--wait", "-1"], "--wait"),
    case(["echo", "mover/**"], "not a topic"),
    case(["echo", "hello", "--count", "-1"], "--count"),
    case(["call", "r1", "add", "--list"], "--list takes no procedure"),
    case(["world", WORLD, "--state-rate", "1e9"], "--state-rate: must be a number from 0"),
    case(["world", WORLD, "--lockstep", "--expect", "100000000"], "--expect: must be from 0"),
    case(["gridworld", "{grid.txt}", "--snapshot-every", "-1"], "--snapshot-every"),
    case(["experiment", "foraging", "--agents", "100000000"], "--agents must be at most"),
    case(
        ["experiment", "levy", "--robots", "100000000"],
        "--targets, --robots and --check-robots must be at most 1000",
    ),
    case(["experiment", "levy", "--workers", "100000"], "--workers must be from 1 to 64"),
    case(["experiment", "levy", "--scale", "nan"], "must be positive and finite"),
    case(["experiment", "eyebot", "--duration", "inf"], "--duration must be from 10"),
    case(
        ["experiment", "maze", "--p", "nan"],
        "--p",
    ),
    case(
        ["ps", "--wait", "inf"],
        "--wait",
    ),
    case(
        [
            "router",
            "--gen-config",
            "{existing}/gen",
            "--team",
            "t",
            "--members",
            "a",
            "--port",
            "99999",
        ],
        "--port",
    ),
    # files: missing, a directory, not UTF-8, the wrong shape, endless
    case(["world", "/nonexistent.toml"], "cannot read"),
    case(["world", "{adir}"], "Is a directory"),
    case(["world", "{latin1.toml}"], "not valid TOML"),
    case(
        ["world", "{latin1.json}"],
        "UTF-8",
    ),
    case(["gridworld", "/nonexistent.txt"], "No such file"),
    case(["gridworld", "{adir}"], "Is a directory"),
    case(["gridworld", "{latin1.txt}"], "not UTF-8"),
    case(["demo", "--world", "{adir}"], "Is a directory"),
    case(["demo", "--world", "{latin1.toml}"], "not valid TOML"),
    case(["router", "--config", "/nonexistent"], "cannot read zenoh settings"),
    case(["router", "--config", "{latin1.json}"], "not UTF-8"),
    case(["router", "--config", "{adir}"], "Is a directory"),
    case(["router", "--config", "{deep.json}"], "nested too deeply"),
    case(
        ["router", "--gen-config", "{existing}", "--team", "t", "--members", "a"],
        "{existing}",
    ),
    case(["robot", "--name", "r9", "--team-file", "/nonexistent.toml"], "No such file"),
    case(["robot", "--name", "r9", "--team-file", "{adir}"], "Is a directory"),
    case(["robot", "--name", "r9", "--team-file", "{teamnum.toml}"], "must be an array"),
    case(
        ["robot", "--name", "r9", "--team-file", "{latin1.toml}"],
        "team file",
    ),
    case(
        ["experiment", "maze", "--maze", "{latin1.json}"],
        "UTF-8",
    ),
    case(["keygen", "--team", "t", "--out", "{adir}"], "Is a directory"),
    case(["replay", "/nonexistent"], "no such file"),
    case(["replay", "{latin1.json}"], "not a recording"),
    # the environment: key files, zenoh settings, timeouts
    case(["ps"], "cannot read MOVER_TEAM_KEY_FILE", {**KEYLESS, "MOVER_TEAM_KEY_FILE": "{adir}"}),
    case(["ps"], "not UTF-8", {**KEYLESS, "MOVER_TEAM_KEY_FILE": "{latin1.txt}"}),
    case(["ps"], "larger than", {**KEYLESS, "MOVER_TEAM_KEY_FILE": "/dev/zero"}),
    case(["ps"], "not a hex string", {"MOVER_TEAM_KEY": "zz" * 32}),
    case(["ps"], "bad team name", {"MOVER_TEAM": "a b"}),
    case(["ps"], "cannot read zenoh settings", {"MOVER_ZENOH_CONFIG": "{adir}"}),
    case(["ps"], "larger than", {"MOVER_ZENOH_CONFIG": "/dev/zero"}),
    case(["ps"], "nested too deeply", {"MOVER_ZENOH_CONFIG": "{deep.json}"}),
    case(["ps"], "bad zenoh setting listen", {"MOVER_LISTEN": "garbage"}),
    case(["ps"], "$MOVER_LEASE_MS must be an integer", {"MOVER_LEASE_MS": "nan"}),
    case(["ps"], "$MOVER_LEASE_MS must be from", {"MOVER_LEASE_MS": "99999999999"}),
    case(["ps"], "$MOVER_HELLO_TIMEOUT must be from", {"MOVER_HELLO_TIMEOUT": "-1"}),
    case(["robot", "--name", "r9"], "$MOVER_LEAVE_GRACE must be", {"MOVER_LEAVE_GRACE": "inf"}),
]


@dataclass
class Refusal:
    """What ``mover`` did with one bad input."""

    status: int | None  # None: still running after the case's bound (then killed)
    out: str
    err: str
    took: float
    said: str  # the case's expected words, its file names filled in


async def _refuse(
    c: Cluster, files: dict[str, str], args: list[str], env: dict[str, str | None], said: str,
    bound: float,
) -> Refusal:  # fmt: skip
    def filled(text: str) -> str:
        for name, path in files.items():
            text = text.replace("{" + name + "}", path)
        return text

    environ = {**os.environ, **c.env, **c.team.env(), **c.peer.env()}
    for name, value in env.items():
        if value is None:
            environ.pop(name, None)
        else:
            environ[name] = filled(value)
    t0 = time.monotonic()
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover", *map(filled, args), env=environ, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    try:
        out, err = await asyncio.wait_for(proc.communicate(), bound)
        status = proc.returncode
    except TimeoutError:
        proc.kill()
        out, err = await proc.communicate()
        status = None
    took = time.monotonic() - t0
    return Refusal(
        status, out.decode(errors="replace"), err.decode(errors="replace"), took, filled(said)
    )


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def refusals(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Refusal]:
    """Every case, run two at a time (the machine has two cores) against a live team."""
    files = _files(tmp_path_factory.mktemp("bad_inputs"))
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        await c.start("robots", "--name", "r1", "--hardware", "none")
        await node.membership.wait_for({"r1"}, timeout=20)
        slots = asyncio.Semaphore(2)

        async def one(params: Any) -> Refusal:
            async with slots:
                return await _refuse(c, files, *params.values)

        done = await asyncio.gather(*(one(p) for p in CASES))
    return {p.id: r for p, r in zip(CASES, done, strict=True)}


@pytest.mark.asyncio(loop_scope="module")
@pytest.mark.parametrize(("args", "env", "said", "bound"), CASES)
async def test_a_bad_input_gets_one_line(
    refusals: dict[str, Refusal],
    request: pytest.FixtureRequest,
    args: list[str],
    env: dict[str, str | None],
    said: str,
    bound: float,
) -> None:
    got = refusals[request.node.callspec.id]
    text = got.out + got.err
    assert got.status is not None, f"still running after {bound} s: {text}"
    assert got.status != 0, text
    assert "Traceback" not in text, text
    errors = [
        line for line in got.err.splitlines() if line.startswith("mover") and got.said in line
    ]
    assert len(errors) == 1, text  # said once, in one line
    written = [line for line in got.err.splitlines() if line.strip()]
    assert len(written) <= 1, got.err  # and nothing else: no warning or log line beside it
    assert got.took < bound
