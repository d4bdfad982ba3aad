"""Every command of the README's shell blocks is run: here, in a bounded form (``--help``,
``--check``, ``make -n``, a verb that only writes files), or by the test this file names for it.

:data:`COMMANDS` is the table. A command added to the README that it does not list fails
:func:`test_every_readme_command_is_run_here_or_by_a_named_test`, so that no README command goes
untested; an entry whose command left the README, or whose test is gone, fails it too. The
README's inline commands (in backticks) name verbs that exist and files that do.
"""

from __future__ import annotations

import ast
import os
import re
import shlex
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
SHELL = re.compile(r"^```sh\n(.*?)^```$", re.MULTILINE | re.DOTALL)
INLINE = re.compile(r"`((?:mover|python|\.venv/bin/python) [^`]+)`")


@dataclass(frozen=True)
class Here:
    """Run by :func:`test_the_cheap_readme_commands_run`: the README's words, with ``before``
    put after the program's name and ``after`` at the end (the bound), in a fresh folder;
    it exits 0 and its output holds ``says``."""

    says: str
    before: tuple[str, ...] = ()
    after: tuple[str, ...] = ()


@dataclass(frozen=True)
class Elsewhere:
    """Run by another test (``path::name``), which runs the command or its exact equivalent."""

    test: str


@dataclass(frozen=True)
class Checked:
    """Not a project command (an install): what it names is checked here, see
    :func:`test_the_view_extra_is_what_the_readme_installs`."""

    test: str


COMMANDS: dict[str, Here | Elsewhere | Checked] = {
    "make demo": Here("mover demo", before=("-n",)),
    "make test": Here("-m pytest -q", before=("-n",)),
    "pip install -e .[view]": Checked("test_the_view_extra_is_what_the_readme_installs"),
    "mover up teams/search_and_rescue.toml": Here("search_and_rescue", after=("--check",)),
    "MOVER_TEAM=rescue MOVER_TEAM_KEY_FILE=runs/.../team.key "
    "MOVER_CONNECT=tcp/127.0.0.1:PORT mover view": Elsewhere(
        "tests/sim_hw/view/test_view_cli.py::test_view_waits_shows_loses_and_shows_again_a_world"
    ),
    "mover router --gen-config team-alpha --team alpha --members ernst,hugo --host 10.0.0.5": (
        Here("team-alpha")
    ),
    "mover router --config team-alpha/router.json": Elsewhere(
        "tests/mover/test_router.py::"
        "test_members_talk_through_a_secured_router_and_outsiders_cannot_connect"
    ),
    "MOVER_MODE=client MOVER_ZENOH_CONFIG=team-alpha/member-ernst.json mover robot --name ernst": (
        Elsewhere(
            "tests/netlab/test_hosts_up.py::test_one_team_file_two_hosts_and_a_run_from_a_third"
        )
    ),
    # The benchmarks are not run by the tests (minutes each, and they load the machine): their
    # options are checked against the README's; bench/team.py's load runs at a small size.
    ".venv/bin/python bench/rpc.py": Here("usage: rpc.py", after=("--help",)),
    ".venv/bin/python bench/collectives.py": Here("usage: collectives.py", after=("--help",)),
    ".venv/bin/python bench/sim.py": Here("usage: sim.py", after=("--help",)),
    ".venv/bin/python bench/floors.py": Here("usage: floors.py", after=("--help",)),
    ".venv/bin/python bench/radio.py": Here("usage: radio.py", after=("--help",)),
    ".venv/bin/python bench/team.py": Elsewhere(
        "tests/mover/test_load.py::test_ten_members_under_call_load_lose_no_reply_and_see_no_flap"
    ),
    ".venv/bin/python bench/repeats.py --stalls": Here("--stalls", after=("--help",)),
    "sudo .venv/bin/python bench/network.py --scenario all": Here("--scenario", after=("--help",)),
}
"""Each command of the README's shell blocks (as :func:`readme_commands` reads it), and how it
is run."""


def readme_commands() -> list[str]:
    """The commands of the README's ``sh`` blocks: one a line (``\\`` continuations joined),
    comments dropped, words normalised as the shell splits them."""
    commands = []
    for block in SHELL.findall(README.read_text()):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                commands.append(" ".join(words))
    return commands


def argv(command: str, how: Here) -> tuple[list[str], dict[str, str]]:
    """The process ``how`` runs for the README's ``command``, and its environment."""
    words = shlex.split(command)
    env = dict(os.environ)
    while "=" in words[0]:
        name, value = words.pop(0).split("=", 1)
        env[name] = value
    if words[0] == "sudo":  # only a bounded form runs here: no root needed
        words.pop(0)
    program = {
        "mover": [sys.executable, "-m", "mover"],
        "python": [sys.executable],
        ".venv/bin/python": [sys.executable],
        "make": ["make", "-C", str(ROOT)],
    }[words[0]]
    return [*program, *how.before, *words[1:], *how.after], env


def _test_exists(node: str) -> bool:
    path, name = node.split("::")
    tree = ast.parse((ROOT / path).read_text())
    defined = (ast.FunctionDef, ast.AsyncFunctionDef)
    return any(isinstance(n, defined) and n.name == name for n in ast.walk(tree))


def test_every_readme_command_is_run_here_or_by_a_named_test() -> None:
    commands = readme_commands()
    assert commands, "no shell block found in README.md"
    untested = [c for c in commands if c not in COMMANDS]
    assert not untested, (
        f"README commands that no test runs: {untested}; run each in tests/docs/test_readme.py "
        "(COMMANDS: Here) or name the test that does (Elsewhere)"
    )
    stale = [c for c in COMMANDS if c not in commands]
    assert not stale, f"COMMANDS lists what the README no longer says: {stale}"
    for command, how in COMMANDS.items():
        if isinstance(how, Elsewhere):
            assert _test_exists(how.test), f"{command!r}: no test {how.test}"
        if isinstance(how, Checked):
            assert how.test in globals(), f"{command!r}: no test {how.test} here"


def test_the_view_extra_is_what_the_readme_installs() -> None:
    """``pip install -e '.[view]'``: the extra exists and pins the rerun the README names."""
    (line,) = [c for c in readme_commands() if c.startswith("pip install")]
    extra = line.split("[")[1].rstrip("]")
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    (rerun,) = pyproject["project"]["optional-dependencies"][extra]
    assert rerun.startswith("rerun-sdk")
    said = re.search(r"rerun-sdk (\d+)\.(\d+)", README.read_text())
    assert said is not None
    major, minor = int(said[1]), int(said[2])
    assert rerun == f"rerun-sdk>={major}.{minor},<{major}.{minor + 1}", rerun


def test_the_readmes_inline_commands_name_real_verbs_and_files() -> None:
    """`mover VERB ...` in the prose names an installed verb, and a repository path it gives
    (``teams/...``, ``worlds/...``, ``examples/...``, ``bench/...``) exists."""
    verbs = {e.name for e in entry_points(group="mover.commands")}
    tops = {p.name for p in ROOT.iterdir() if p.is_dir() and not p.name.startswith(".")}
    tops -= {"out", "runs", "site"}  # what commands write, not what they read
    inline = INLINE.findall(README.read_text())
    assert len(inline) > 10, inline
    for command in inline:
        words = command.split()
        if words[0] == "mover":
            verb = next(w for w in words[1:] if not w.startswith("-"))
            assert verb in verbs or verb.isupper(), f"README: `{command}`: no verb {verb!r}"
        for word in words:
            placeholder = "..." in word or re.search("[A-Z]{2}", word)
            if "/" in word and word.split("/")[0] in tops and not placeholder:
                assert (ROOT / word).exists(), f"README: `{command}`: no {word}"


@pytest.mark.processes
@pytest.mark.parametrize(
    "command", [c for c, how in COMMANDS.items() if isinstance(how, Here)], ids=str
)
def test_the_cheap_readme_commands_run(command: str, tmp_path: Path) -> None:
    how = COMMANDS[command]
    assert isinstance(how, Here)
    args, env = argv(command, how)
    env["PYTHONPATH"] = str(ROOT)
    if args[0] != "make":  # the README's paths are the repository's; a command writes in tmp
        args = [str(ROOT / a) if (ROOT / a).is_file() and "/" in a else a for a in args]
    done = subprocess.run(
        args, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60, check=False
    )
    said = done.stdout + done.stderr
    assert done.returncode == 0, f"{args}: {said}"
    assert how.says in said or any(how.says in p.name for p in tmp_path.iterdir()), said
