"""Team files across hosts, read and planned (no process, no network)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mover._up import TeamFileError
from mover._up._hosts import certificate_names, endpoint, generate, member_env, router_args
from mover._up._plan import processes, seeds
from mover._up._teamfile import parse_team

FILE = """\
[team]
name = "rescue"
key_file = "team.key"
{tls}
[[hosts]]
name = "a"
address = "10.0.0.5"

[[hosts]]
name = "b"
address = "10.0.0.6"

[world]
file = "w.toml"
host = "a"

[[robots]]
names = ["elvis", "ernst"]
host = "b"

[[workstations]]
names = ["desk"]
"""


def test_each_host_starts_its_part_and_every_process_joins_through_the_router() -> None:
    plan = parse_team(FILE.format(tls=""), Path("/t/team.toml"))
    assert [h.name for h in plan.hosts if h.router] == ["a"]  # the first, by default
    assert plan.topology == "router"
    assert [m.host for m in plan.members] == ["b", "b", "a"]  # desk: the router's host
    assert endpoint(plan) == "tcp/10.0.0.5:7448"
    s = seeds(plan, 1)
    on_a = processes(plan, s, Path("/run"), port=0, host="a")
    on_b = processes(plan, s, Path("/run"), port=0, host="b")
    assert [p.name for p in on_a] == ["router", "world", "desk"]
    assert [p.name for p in on_b] == ["elvis", "ernst"]
    assert on_a[0].argv[-3:] == ("router", "--listen", "tcp/10.0.0.5:7448")
    assert on_b[0].env == {
        "MOVER_MODE": "client",
        "MOVER_LISTEN": "",
        "MOVER_CONNECT": endpoint(plan),
    }
    assert certificate_names(plan) == ["world", "elvis", "ernst", "desk", "up-a", "up-b"]


def test_with_tls_every_process_has_its_own_certificate(tmp_path: Path) -> None:
    plan = parse_team(FILE.format(tls='tls = "tls"'), tmp_path / "team.toml")
    assert endpoint(plan) == "tls/10.0.0.5:7448"
    written = {p.name for p in generate(plan, tmp_path / "tls")}
    assert {"member-elvis.json", "member-up-b.json", "member-workstation.json"} <= written
    assert router_args(plan) == ["router", "--config", str(tmp_path / "tls" / "router.json")]
    env = member_env(plan, "elvis")
    assert env["MOVER_ZENOH_CONFIG"] == str(tmp_path / "tls" / "member-elvis.json")
    assert env["MOVER_MODE"] == "client" and env["MOVER_CONNECT"] == ""


@pytest.mark.parametrize(
    ("change", "problem"),
    [
        (('host = "b"\n', 'host = "c"\n'), "robots[0].host: 'c' is no host of [[hosts]]"),
        (('address = "10.0.0.6"', 'address = "a b"'), "hosts[1].address: must be a host name"),
        (('name = "b"\naddress', 'name = "a"\naddress'), "hosts[1].name: 'a' is listed twice"),
        (('key_file = "team.key"\n', 'topology = "peer"\n'), "team.topology: a team across"),
    ],
)
def test_a_wrong_placement_is_refused_at_its_line(change: tuple[str, str], problem: str) -> None:
    text = FILE.format(tls="").replace(*change)
    with pytest.raises(TeamFileError, match=problem.replace("[", r"\[").replace("]", r"\]")):
        parse_team(text, Path("/t/team.toml"))


def test_a_host_without_hosts_is_refused() -> None:
    text = '[team]\nname = "t"\n[[workstations]]\nnames = ["w"]\nhost = "a"\n'
    with pytest.raises(TeamFileError, match="names host 'a' but the file has no"):
        parse_team(text, Path("/t/team.toml"))
