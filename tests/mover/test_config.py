"""Team and transport settings: clear errors for bad input (no network)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mover import NodeConfig, TeamCredentials


def test_team_from_env(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("MOVER_TEAM", raising=False)
    monkeypatch.delenv("MOVER_TEAM_KEY", raising=False)
    monkeypatch.delenv("MOVER_TEAM_KEY_FILE", raising=False)
    with pytest.raises(ValueError, match="no team"):
        TeamCredentials.from_env()
    with pytest.raises(ValueError, match="no key for team 'alpha'"):
        TeamCredentials.from_env("alpha")
    monkeypatch.setenv("MOVER_TEAM_KEY", "zz")
    with pytest.raises(ValueError, match="not a hex string"):
        TeamCredentials.from_env("alpha")
    monkeypatch.setenv("MOVER_TEAM_KEY", "00ff")
    with pytest.raises(ValueError, match="at least 16 bytes"):
        TeamCredentials.from_env("alpha")
    monkeypatch.delenv("MOVER_TEAM_KEY")
    key = tmp_path / "key"
    key.write_text("ab" * 32 + "\n")
    monkeypatch.setenv("MOVER_TEAM_KEY_FILE", str(key))
    assert TeamCredentials.from_env("alpha").key == b"\xab" * 32
    monkeypatch.setenv("MOVER_TEAM_KEY_FILE", str(tmp_path / "missing"))
    with pytest.raises(ValueError, match="cannot read MOVER_TEAM_KEY_FILE"):
        TeamCredentials.from_env("alpha")
    with pytest.raises(ValueError, match="bad team name"):
        TeamCredentials("a/b", b"k" * 32)


def test_node_config(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("MOVER_MODE", "client")
    monkeypatch.setenv("MOVER_CONNECT", "tcp/127.0.0.1:7447,tcp/127.0.0.1:7448")
    monkeypatch.delenv("MOVER_LISTEN", raising=False)
    config = NodeConfig.from_env()
    assert config.mode == "client" and config.listen == ()
    assert config.connect == ("tcp/127.0.0.1:7447", "tcp/127.0.0.1:7448")
    assert NodeConfig(**{**config.__dict__}).to_zenoh() is not None
    with pytest.raises(ValueError, match="bad zenoh mode 'bus'"):
        NodeConfig(mode="bus").to_zenoh()
    bad = tmp_path / "z.json"
    bad.write_text("[1, 2]")
    monkeypatch.setenv("MOVER_ZENOH_CONFIG", str(bad))
    with pytest.raises(ValueError, match="expected an object"):
        NodeConfig.from_env()
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="cannot read zenoh settings"):
        NodeConfig.from_env()
