"""The `mover` command against real robot processes, and the CLI toolkit of ``mover.cli``."""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import os
import sys
from typing import Any

import pytest

from mover import Node, TeamCredentials
from mover.cli import (
    LOG_LEVEL_ENV,
    UsageError,
    add_command,
    add_log_arguments,
    add_team_arguments,
    setup_logging,
    team_from_args,
)
from tests.helpers.procs import ROOT, cluster

pytestmark = pytest.mark.processes


async def mover(
    *args: str, env: dict[str, str], module: str = "mover._cli"
) -> tuple[int, str, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        module,
        *args,
        env={**os.environ, **env},
        cwd=ROOT,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    out, err = await asyncio.wait_for(proc.communicate(), 60)
    return proc.returncode or 0, out.decode(), err.decode()


async def test_ps_and_call() -> None:
    async with cluster() as c, Node("tester", c.team, kind="test", config=c.seed) as node:
        await c.robot("r1", "--kind", "foot-bot")
        await node.membership.wait_for({"r1"}, timeout=10)
        env = {**c.team.env(), **c.peer.env()}
        code, out, err = await mover("ps", "--wait", "1.5", "--json", env=env)
        assert code == 0, err
        rows = {r["name"]: r for r in map(json.loads, out.splitlines())}
        assert rows["r1"]["kind"] == "foot-bot" and rows["tester"]["kind"] == "test"
        assert not any(n.startswith("ps-") for n in rows)  # the tool is not a member

        code, out, err = await mover("call", "r1", "add", "2", "40", env=env)
        assert (code, out) == (0, "42\n"), err
        code, _, err = await mover("call", "r1", "boom", '"no"', env=env)
        assert code == 1 and "RemoteError" in err and "ValueError: no" in err
        code, _, err = await mover("call", "r1", "add", "1", env=env)
        assert code == 1 and "BadArguments" in err
        code, _, err = await mover("call", "r9", "add", "1", "--wait", "0.5", env=env)
        assert code == 1 and "no member 'r9'" in err
        code, _, err = await mover("call", "r1", "add", "two", env=env)
        assert code == 2 and "argument 1 is not JSON" in err
        wrong = {**env, "MOVER_TEAM_KEY": "00" * 32}
        code, _, err = await mover("call", "r1", "add", "1", "2", env=wrong)
        assert code == 1 and "no member 'r1'" in err  # an outsider cannot even see members


# -- the toolkit, without processes ---------------------------------------------------------------


def _team_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser()
    add_team_arguments(p)
    return p


def test_a_command_runs_its_function_and_describes_itself_by_its_docstring() -> None:
    def hello(args: argparse.Namespace) -> int:
        """Say hello to NAME, once."""
        return len(args.name)

    parser = argparse.ArgumentParser(prog="mover")
    sub = parser.add_subparsers()
    add_command(sub, "hello", hello, "greet").add_argument("name")
    add_command(sub, "bye", hello, "part", "Say goodbye.").add_argument("name")
    args = parser.parse_args(["hello", "ada"])
    assert args.func is hello and args.func(args) == 3
    assert "Say hello to NAME, once." in sub.choices["hello"].format_help()
    assert "Say goodbye." in sub.choices["bye"].format_help()
    assert "greet" in parser.format_help() and "part" in parser.format_help()


def test_team_arguments_default_to_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    args = _team_parser().parse_args([])
    assert (args.team, args.connect) == (None, None)
    team = TeamCredentials.generate("alpha")
    for name, value in team.env().items():
        monkeypatch.setenv(name, value)
    monkeypatch.setenv("MOVER_CONNECT", "tcp/127.0.0.1:7001")
    got, config = team_from_args(args)
    assert (got.name, got.key) == ("alpha", team.key)
    assert config.connect == ("tcp/127.0.0.1:7001",)


def test_team_arguments_override_and_repeat(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOVER_TEAM", "alpha")
    monkeypatch.setenv("MOVER_TEAM_KEY", "ab" * 32)
    monkeypatch.delenv("MOVER_CONNECT", raising=False)
    argv = ["--team", "beta", "--connect", "tcp/127.0.0.1:1", "--connect", "tcp/127.0.0.1:2"]
    team, config = team_from_args(_team_parser().parse_args(argv))
    assert team.name == "beta"
    assert config.connect == ("tcp/127.0.0.1:1", "tcp/127.0.0.1:2")


def test_a_missing_team_is_a_usage_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MOVER_TEAM", raising=False)
    with pytest.raises(UsageError, match="no team"):
        team_from_args(_team_parser().parse_args([]))


@pytest.mark.parametrize(
    ("argv", "env", "default", "level"),
    [
        ([], None, "WARNING", logging.WARNING),
        ([], None, "INFO", logging.INFO),
        ([], "debug", "WARNING", logging.DEBUG),
        (["-v"], "ERROR", "WARNING", logging.INFO),
        (["-vv"], None, "WARNING", logging.DEBUG),
        (["-vvv"], None, "WARNING", logging.DEBUG),
        (["--log-level", "error"], "DEBUG", "WARNING", logging.ERROR),
        (["-v", "--log-level", "CRITICAL"], None, "WARNING", logging.CRITICAL),
    ],
)
def test_one_way_to_set_the_log_level(
    monkeypatch: pytest.MonkeyPatch, argv: list[str], env: str | None, default: str, level: int
) -> None:
    if env is None:
        monkeypatch.delenv(LOG_LEVEL_ENV, raising=False)
    else:
        monkeypatch.setenv(LOG_LEVEL_ENV, env)
    configured: dict[str, Any] = {}
    monkeypatch.setattr(logging, "basicConfig", lambda **kw: configured.update(kw))
    p = argparse.ArgumentParser()
    add_log_arguments(p)
    assert setup_logging(p.parse_args(argv), default=default) == level
    assert configured["level"] == level


def test_a_wrong_log_level_is_refused(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    p = argparse.ArgumentParser()
    add_log_arguments(p)
    with pytest.raises(SystemExit) as exited:
        p.parse_args(["--log-level", "loud"])
    assert exited.value.code == 2 and "unknown log level 'loud'" in capsys.readouterr().err
    monkeypatch.setenv(LOG_LEVEL_ENV, "loud")
    with pytest.raises(UsageError, match=r"\$MOVER_LOG_LEVEL: unknown log level 'loud'"):
        setup_logging(p.parse_args([]))


def test_the_old_home_of_usage_error_still_works() -> None:
    from mover._cli import UsageError as Old

    assert Old is UsageError


async def test_python_dash_m_mover_is_the_mover_command() -> None:
    env = {"MOVER_TEAM": "alpha", "MOVER_TEAM_KEY": "ab" * 32}
    code, out, _ = await mover("--help", env=env, module="mover")
    assert code == 0 and "usage: mover" in out and "--log-level" in out
    code, out, err = await mover("call", "r1", "add", "two", env=env, module="mover")
    # one line for the mistake (a verb that fails to load would add its own line before it)
    assert (code, out) == (2, "") and [
        line for line in err.splitlines() if line.startswith("mover call:")
    ] == [
        "mover call: argument 1 is not JSON (Expecting value): 'two'; quote strings as '\"text\"'"
    ]
    code, _, err = await mover("ps", env={**env, LOG_LEVEL_ENV: "loud"}, module="mover")
    assert code == 2 and "mover ps: $MOVER_LOG_LEVEL: unknown log level 'loud'" in err
