"""The READY line of a world process names endpoints that reach it, never a port 0."""

from __future__ import annotations

from mover import NodeConfig, TeamCredentials
from sim_hw._process import ready_line

TEAM = TeamCredentials("lab", bytes(32))


def test_a_free_port_is_not_shown_the_endpoints_it_connects_to_are() -> None:
    config = NodeConfig(listen=("tcp/127.0.0.1:0",), connect=("tcp/127.0.0.1:7447",))
    line = ready_line("world", "w.toml", TEAM, config)
    assert ":0" not in line
    assert "MOVER_TEAM=lab MOVER_CONNECT=tcp/127.0.0.1:7447" in line


def test_a_fixed_listen_port_is_shown() -> None:
    config = NodeConfig(listen=("tcp/127.0.0.1:7500",), connect=("tcp/127.0.0.1:7447",))
    assert "MOVER_CONNECT=tcp/127.0.0.1:7500 " in ready_line("world", "w.toml", TEAM, config)


def test_nothing_known_names_the_team_only() -> None:
    line = ready_line("world", "w.toml", TEAM, NodeConfig(listen=("tcp/127.0.0.1:0",)))
    assert "robots join with MOVER_TEAM=lab and the team's key" in line
