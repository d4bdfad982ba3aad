"""Team files: what a good one plans, and a one-line error naming the line for bad ones."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mover._exceptions import ConfigError
from mover._keylines import KeyLines
from mover._up import needs_router
from mover._up._plan import PEER_MESH_MAX, derive, members, processes, seeds, uses_router
from mover._up._playground import READY
from mover._up._teamfile import MAX_PROCESSES, TeamFileError, TeamPlan, load_team, parse_team

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]

GOOD = """\
[team]
name = "alpha"
seed = 7

[world]
file = "arena.toml"
timeout = 5

[[robots]]
prefix = "r"
count = 3
spec = { radius = 0.2 }
options = { call_timeout = 60 }
placement = { start = [1.0, 1.0, 90], step = [0.5, 0] }

[[robots]]
names = ["scout"]
kind = "scout"
required = true

[[workstations]]
names = ["desk"]

[program]
name = "hello_team"
args = { range = 2.5 }
survivors = true
"""


def parse(text: str, name: str = "team.toml") -> object:
    return parse_team(text, Path("/teams") / name)


def test_a_good_file_plans_its_processes(tmp_path: Path) -> None:
    plan = parse_team(GOOD, tmp_path / "team.toml")
    assert plan.name == "alpha" and plan.seed == 7
    assert plan.world is not None and plan.world.file == tmp_path / "arena.toml"
    assert plan.world.lockstep and plan.world.expect == 4  # the four sim robots
    names = [m.name for m in plan.members]
    assert names == ["r1", "r2", "r3", "scout", "desk"]
    assert plan.robots() == ["r1", "r2", "r3", "scout"]
    r2 = plan.members[1]
    assert r2.spec == {"radius": 0.2, "pose": [1.5, 1.0, 90.0]} and r2.world == "world"
    assert plan.members[3].required and not plan.members[0].required
    assert plan.members[4].hardware == "none" and plan.members[4].kind == "workstation"
    assert plan.program is not None and plan.program.survivors and not plan.program.share
    s = seeds(plan)
    assert (s.run, s.world, s.program) == (7, derive(7, "world"), derive(7, "program"))
    assert seeds(plan, 8).world != s.world  # the command line's seed wins
    procs = processes(plan, s, tmp_path, port=7000)
    assert [p.name for p in procs] == ["world", "r1", "r2", "r3", "scout", "desk"]
    world = procs[0].argv
    assert world[-11:] == (
        *("world", str(tmp_path / "arena.toml"), "--name", "world", "--seed", str(s.world)),
        *("--lockstep", "--expect", "4", "--timeout", "5"),
    )
    r1 = " ".join(procs[1].argv)
    assert "--hardware sim --world world --spec" in r1 and "--option call_timeout=60" in r1
    assert procs[5].argv[-6:] == ("--name", "desk", "--kind", "workstation", "--hardware", "none")


def test_a_world_takes_a_control_delay(tmp_path: Path) -> None:
    plan = parse_team(GOOD.replace("timeout = 5", "control_delay = 2"), tmp_path / "team.toml")
    assert plan.world is not None and plan.world.control_delay == 2
    world = processes(plan, seeds(plan), tmp_path, port=7000)[0].argv
    assert world[-5:] == ("--lockstep", "--control-delay", "2", "--expect", "4")


def test_a_large_team_gets_a_router_and_a_file_may_choose(tmp_path: Path) -> None:
    assert not needs_router(PEER_MESH_MAX) and needs_router(PEER_MESH_MAX + 1)
    big = '[team]\nname = "big"\n[[workstations]]\nprefix = "w"\ncount = 12\n'
    plan = parse_team(big, tmp_path / "t.toml")
    assert members(plan) == 13 and uses_router(plan)  # twelve and mover up itself
    procs = processes(plan, seeds(plan, 1), tmp_path, port=7001)
    assert procs[0].name == "router" and not procs[0].member and procs[0].required
    assert "tcp/127.0.0.1:7001" in procs[0].argv
    small = parse_team(big.replace("12", "2"), tmp_path / "t.toml")
    assert not uses_router(small)
    forced = parse_team(big.replace("count = 12", "count = 2").replace(
        'name = "big"', 'name = "big"\ntopology = "router"'), tmp_path / "t.toml")  # fmt: skip
    assert uses_router(forced)
    peer = parse_team(big.replace('name = "big"', 'name = "big"\ntopology = "peer"'), tmp_path)
    assert not uses_router(peer)


def test_a_grid_world_and_its_robots(tmp_path: Path) -> None:
    text = (
        '[team]\nname = "ants"\n[world]\nkind = "grid"\nfile = "f.json"\n'
        'layout = { base = [6, 6] }\nuntil = "delivered"\n'
        '[[robots]]\nprefix = "f"\ncount = 2\nspec = { view = 0 }\n'
        '[program]\nname = "foraging"\nargs = { method = "cmarking" }\n'
    )
    plan = parse_team(text, tmp_path / "t.toml")
    assert plan.world is not None and plan.world.name == "gridworld" and plan.world.expect == 2
    procs = processes(plan, seeds(plan, 3), tmp_path, port=7002)
    assert procs[0].argv[3:5] == ("gridworld", str(tmp_path / "f.json"))
    assert '--layout {"base": [6, 6]}' in " ".join(procs[0].argv)
    assert "--hardware grid --world gridworld" in " ".join(procs[1].argv)


BAD = [
    # (text, line, what the error says)
    ('[team]\nname = "a"\nsede = 1\n', 3, "team.sede: unknown key (did you mean 'seed'?)"),
    (
        '[team]\nname = "a"\n[[robots]]\nprefix = "r"\ncount = 2\n[[robots]]\nprefix = "s"\n'
        "count = 1000\n",
        8,
        f"robots[1].count: must be from 1 to {MAX_PROCESSES}",
    ),
    (
        '[team]\nname = "a"\n[[robots]]\nnames = ["x"]\n[[robots]]\nnames = ["y", "x"]\n',
        5,
        "robots[1]: the name 'x' is taken",
    ),
    ('[team]\nname = "a"\n[[robots]]\nnames = ["up"]\n', 3, "taken by mover up itself"),
    (
        '[team]\nname = "a"\n[world]\nfile = "w.toml"\nlockstep = true\nspeed = 2\n',
        6,
        "world.speed: a lock-step world has no speed",
    ),
    (
        '[team]\nname = "a"\n[world]\nkind = "grid"\nfile = "g.json"\nrecord = true\n',
        6,
        "world.record: unknown key in a grid world",
    ),
    (
        '[team]\nname = "a"\n[[robots]]\nnames = ["r"]\n\n[program]\nname = "p"\nmembers = ["q"]\n',
        8,
        "program.members[0]: 'q' is no member",
    ),
    (
        '[team]\nname = "a"\n[[robots]]\nnames = ["r1", "r2"]\nposes = [[1, 2, 0]]\n',
        5,
        "robots[0].poses: must be a list of 2 poses",
    ),
    ('[team]\nname = "a b"\n', 2, "team.name: bad member name"),
    ('[team]\nname = "a"\nseed = -1\n', 3, "team.seed: must be from 0"),
    (
        '[team]\nname = "a"\ntopology = "star"\n',
        3,
        "team.topology: must be 'auto', 'peer' or 'router', got 'star'",
    ),
    ('[team]\nname = "a"\n[world]\nfile = "w.toml"\n[world.x]\n', 5, "world.x: unknown key"),
    ('[team]\nname = "a"\nseed = = 1\n', 3, "not valid TOML"),
    ('[tema]\nname = "a"\n', 1, "tema: unknown key (did you mean 'team'?)"),
    (
        '[team]\nname = "a"\n[[workstations]]\nprefix = "w"\ncount = 150\n'
        '[[robots]]\nprefix = "r"\ncount = 60\n',
        3,  # robots are counted first: the workstations cross the bound
        "workstations[0]: more than 200 processes",
    ),
]


@pytest.mark.parametrize(("text", "line", "said"), BAD, ids=[b[2][:30] for b in BAD])
def test_a_bad_file_names_its_line(text: str, line: int, said: str) -> None:
    with pytest.raises(TeamFileError) as caught:
        parse(text)
    message = str(caught.value)
    assert message.startswith(f"/teams/team.toml:{line}: "), message
    assert said in message, message
    assert "\n" not in message


def test_no_team_table_and_an_unreadable_file(tmp_path: Path) -> None:
    with pytest.raises(TeamFileError, match=r"needs a \[team\] table"):
        parse("[[robots]]\nnames = ['r']\n")
    with pytest.raises(TeamFileError, match="cannot read"):
        load_team(tmp_path / "missing.toml")


def test_key_lines_follow_arrays_of_tables_and_dotted_keys() -> None:
    text = (
        "[team]\nname = 'a'\n"  # 1-2
        "[[robots]]\nprefix = 'r'\n"  # 3-4
        "[[robots]]\n"  # 5
        "spec.radius = 0.2\n"  # 6
        'text = """\nfake = 1\n"""\n'  # 7-9: a multi-line string is no key
        "poses = [\n  [1, 2, 3],\n]\n"  # 10-12
        "count = 2  # trailing\n"  # 13
        "[robots.options]\ncall_timeout = 1\n"  # 14-15: a sub-table of the last robots entry
    )
    lines = KeyLines(text)
    assert lines.line(("team", "name")) == 2
    assert lines.line(("robots", 0, "prefix")) == 4
    assert lines.line(("robots", 1)) == 5
    assert lines.line(("robots", 1, "spec", "radius")) == 6
    assert lines.line(("robots", 1, "fake")) == 5  # not a key: the nearest enclosing one
    assert lines.line(("robots", 1, "poses", 1)) == 10
    assert lines.line(("robots", 1, "count")) == 13
    assert lines.line(("robots", 1, "options", "call_timeout")) == 15


def test_the_command_line_says_one_line_for_a_bad_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[team]\nname = "a"\n[[robots]]\nnames = ["r"]\ncuont = 3\n')
    done = subprocess.run(
        [sys.executable, "-m", "mover._up", str(bad)],
        capture_output=True, text=True, timeout=30, cwd=ROOT,
    )  # fmt: skip
    assert done.returncode == 2
    assert "Traceback" not in done.stderr + done.stdout
    assert done.stderr.strip().splitlines() == [
        f"mover up: {bad}:5: robots[0].cuont: unknown key in a robot group (did you mean "
        "'count'?); known: names, prefix, count, first, kind, required, hardware, world, spec, "
        "options, poses, placement, host"
    ]


def test_the_demo_team_file_checks() -> None:
    plan = load_team(ROOT / "teams" / "search_and_rescue.toml")
    assert plan.world is not None and plan.world.lockstep and plan.world.expect == 3
    assert plan.robots() == ["elvis", "ernst", "moseley"]
    assert plan.program is not None and plan.program.name == "search_and_rescue"


def test_a_world_expects_every_robot_pointed_at_it_whatever_its_backend() -> None:
    plan = load_team(ROOT / "teams" / "stigmergic_navigation.toml")  # no expect in the file
    kinds = {m.hardware for m in plan.members}
    assert kinds == {"eyebot", "footbot"} and len(plan.members) == 16
    assert plan.world is not None and plan.world.expect == 16
    assert plan.program is not None and plan.program.survivors


def test_check_prints_the_plan_and_starts_nothing(tmp_path: Path) -> None:
    (tmp_path / "t.toml").write_text(GOOD)
    done = subprocess.run(
        [sys.executable, "-m", "mover._up", str(tmp_path / "t.toml"), "--check"],
        capture_output=True, text=True, timeout=30, cwd=ROOT,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == (
        f"{tmp_path / 't.toml'}: team 'alpha', 6 processes and mover up itself: 7 members "
        "(auto: peer mesh), "
        f"continuous world {tmp_path / 'arena.toml'}"
    )
    assert "  scout: scout, hardware sim (required)" in lines
    assert "  desk: workstation, hardware none" in lines
    assert not list((ROOT / "runs").glob("alpha-*"))  # no run folder: nothing started


# -- an Aseba Playground world -------------------------------------------------------------------

PLAYGROUND_WORLD = """\
<aseba-playground>
  <world w="100" h="100"/>
  <robot type="thymio2" x="20" y="20" port="33333" name="t1" nodeId="1"/>
  <robot type="thymio2" x="20" y="60" port="33334" name="t2" nodeId="1"/>
</aseba-playground>
"""
PLAYGROUND_TEAM = """\
[team]
name = "thymios"
[world]
kind = "playground"
file = "w.playground"
ports = "{ports}"
[[robots]]
names = ["t1", "t2"]
options = {{ tick_period = 0.1 }}
[[workstations]]
names = ["desk"]
"""


def _playground_team(tmp_path: Path, text: str) -> TeamPlan:
    (tmp_path / "w.playground").write_text(PLAYGROUND_WORLD)
    (tmp_path / "empty.playground").write_text("<aseba-playground/>\n")
    return parse_team(text, tmp_path / "team.toml")


@pytest.fixture
def aseba(monkeypatch: pytest.MonkeyPatch) -> None:
    """``asebaplayground`` counts as installed (a unit test starts nothing)."""
    monkeypatch.setattr(shutil, "which", lambda name: f"/usr/bin/{name}")


@pytest.mark.parametrize("choice", ["free", "file"])
def test_a_playground_world_starts_first_and_links_each_robot_by_name(
    tmp_path: Path, aseba: None, choice: str
) -> None:
    plan = _playground_team(tmp_path, PLAYGROUND_TEAM.format(ports=choice))
    w = plan.world
    assert w is not None and w.kind == "playground" and w.name == "playground"
    assert w.robots == {"t1": 33333, "t2": 33334} and not w.lockstep and w.ports == choice
    assert [(m.name, m.hardware, m.world) for m in plan.members] == [
        ("t1", "thymio", None), ("t2", "thymio", None), ("desk", "none", None)
    ]  # fmt: skip
    assert members(plan) == 4  # the Playground is no member: t1, t2, desk and mover up
    world, *rest = processes(plan, seeds(plan, 1), tmp_path, port=7003)
    assert world.argv[3:5] == ("playground", str(tmp_path / "w.playground"))
    assert not world.member and world.ready_line == READY and world.stage == 1
    moved = [a for a in world.argv if a.startswith("--port=")]
    links = {p.name: " ".join(p.argv).partition("--option link=")[2] for p in rest}
    if choice == "file":
        assert not moved
        assert links == {"t1": '"tcp:127.0.0.1:33333"', "t2": '"tcp:127.0.0.1:33334"', "desk": ""}
    else:  # free ports, each robot told its own
        ports = dict(a.removeprefix("--port=").split("=") for a in moved)
        assert sorted(ports) == ["t1", "t2"]
        assert links["t1"] == f'"tcp:127.0.0.1:{ports["t1"]}"'
        assert links["t2"] == f'"tcp:127.0.0.1:{ports["t2"]}"'
    assert "--option tick_period=0.1" in " ".join(rest[0].argv)
    assert "--world" not in rest[0].argv


def test_a_playground_world_needs_asebaplayground(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    plan = _playground_team(tmp_path, PLAYGROUND_TEAM.format(ports="free"))
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(ConfigError) as caught:
        processes(plan, seeds(plan, 1), tmp_path, port=7004)
    assert str(caught.value) == (
        '[world] kind = "playground" needs asebaplayground on PATH '
        "(Debian package: aseba; `apt-get install aseba`)"
    )


def test_mover_up_refuses_a_playground_world_without_asebaplayground(tmp_path: Path) -> None:
    (tmp_path / "w.playground").write_text(PLAYGROUND_WORLD)
    (tmp_path / "team.toml").write_text(PLAYGROUND_TEAM.format(ports="free"))
    done = subprocess.run(
        [sys.executable, "-m", "mover._up", str(tmp_path / "team.toml"),
         "--out", str(tmp_path / "run")],
        capture_output=True, text=True, timeout=30, cwd=ROOT, env={**os.environ, "PATH": ""},
    )  # fmt: skip
    assert done.returncode == 1
    assert "Traceback" not in done.stderr + done.stdout
    assert done.stderr.strip().splitlines() == [
        'mover up: [world] kind = "playground" needs asebaplayground on PATH '
        "(Debian package: aseba; `apt-get install aseba`)"
    ]


PLAYGROUND_BAD = [
    # (what replaces a line of PLAYGROUND_TEAM, the line the error names, what it says)
    (("ports = ", "until = 5\n"), 6, "world.until: unknown key in a playground world"),
    (("ports = ", 'ports = "any"\n'), 6, "world.ports: must be 'free' or 'file', got 'any'"),
    (("file = ", 'file = "missing.playground"\n'), 5, "world.file: cannot read"),
    (
        ("file = ", 'file = "empty.playground"\n'),
        5,
        "world.file: " + "{tmp}/empty.playground: no <robot",
    ),
    (("names = ", 'names = ["t1", "t9"]\n'), 8, "robots[0].names[1]: 't9' is no robot of"),
    (
        ("options = ", 'options = { link = "tcp:127.0.0.1:1" }\n'),
        9,
        "robots[0].options: the playground world gives each robot its link",
    ),
    (
        ("options = ", 'hardware = "sim"\n'),
        9,
        "robots[0].hardware: a playground world's robots are thymio, got 'sim'",
    ),
]


@pytest.mark.parametrize(
    ("change", "line", "said"), PLAYGROUND_BAD, ids=[b[2][:30] for b in PLAYGROUND_BAD]
)
def test_a_bad_playground_world_names_its_line(
    tmp_path: Path, change: tuple[str, str], line: int, said: str
) -> None:
    start, new = change
    text = "".join(
        new if ln.startswith(start) else ln
        for ln in PLAYGROUND_TEAM.format(ports="free").splitlines(keepends=True)
    )
    with pytest.raises(TeamFileError) as caught:
        _playground_team(tmp_path, text)
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'team.toml'}:{line}: "), message
    assert said.format(tmp=tmp_path) in message, message
    assert "\n" not in message


def test_the_thymio_team_file_starts_its_playground() -> None:
    plan = load_team(ROOT / "teams" / "thymio_gather.toml")
    assert plan.world is not None and plan.world.kind == "playground"
    assert plan.world.ports == "free" and list(plan.world.robots) == plan.robots()
