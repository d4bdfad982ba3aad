"""How a node reaches the others (NodeConfig) and which team it belongs to (Team).

Default: zenoh peer mode on loopback, multicast scouting off, listening on a free port; peers
find each other by connecting to one or more known endpoints and zenoh's gossip links the rest.
Every process sets a short lease so a hung peer is noticed within about a second.

Environment (read by ``from_env``): ``MOVER_TEAM``, ``MOVER_TEAM_KEY`` (hex) or
``MOVER_TEAM_KEY_FILE``; ``MOVER_MODE`` (peer | client), ``MOVER_LISTEN`` and ``MOVER_CONNECT``
(comma-separated endpoints such as ``tcp/127.0.0.1:7447``), ``MOVER_ZENOH_CONFIG`` (a json5 file
merged over the defaults, e.g. TLS settings written by ``mover router --gen-config``).
"""

from __future__ import annotations

import json
import os
import secrets
import socket
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import zenoh

from ._exceptions import ConfigError
from ._keys import check_name

MIN_KEY_BYTES = 16


@dataclass(frozen=True)
class Team:
    """A team: its name and its secret key (every envelope is sealed under keys derived from it)."""

    name: str
    key: bytes = field(repr=False)

    def __post_init__(self) -> None:
        check_name("team", self.name)
        if not isinstance(self.key, bytes) or len(self.key) < MIN_KEY_BYTES:
            raise ConfigError(f"a team key must be at least {MIN_KEY_BYTES} bytes")

    @classmethod
    def generate(cls, name: str) -> Team:
        """A team with a fresh random 32-byte key."""
        return cls(name, secrets.token_bytes(32))

    @classmethod
    def from_env(cls, name: str | None = None) -> Team:
        """The team named by ``MOVER_TEAM`` (or ``name``) with its key from the environment."""
        name = name or os.environ.get("MOVER_TEAM")
        if not name:
            raise ConfigError("no team: pass --team or set MOVER_TEAM")
        hexkey = os.environ.get("MOVER_TEAM_KEY")
        path = os.environ.get("MOVER_TEAM_KEY_FILE")
        if hexkey is None and path:
            try:
                hexkey = Path(path).read_text().strip()
            except OSError as exc:
                raise ConfigError(f"cannot read MOVER_TEAM_KEY_FILE {path!r}: {exc}") from exc
        if not hexkey:
            raise ConfigError(
                f"no key for team {name!r}: set MOVER_TEAM_KEY (hex) or MOVER_TEAM_KEY_FILE"
            )
        try:
            key = bytes.fromhex(hexkey)
        except ValueError as exc:
            raise ConfigError("MOVER_TEAM_KEY is not a hex string") from exc
        return cls(name, key)

    def env(self) -> dict[str, str]:
        """Environment variables that let a child process join this team."""
        return {"MOVER_TEAM": self.name, "MOVER_TEAM_KEY": self.key.hex()}


@dataclass(frozen=True)
class NodeConfig:
    """Zenoh settings for one node."""

    mode: str = "peer"
    listen: tuple[str, ...] = ("tcp/127.0.0.1:0",)
    connect: tuple[str, ...] = ()
    multicast: bool = False
    lease_ms: int = 1000
    keep_alive: int = 4
    overrides: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_env(cls, connect: Sequence[str] = ()) -> NodeConfig:
        """Settings from ``MOVER_*`` environment variables (see the module docstring).

        ``connect`` adds endpoints to those of ``MOVER_CONNECT`` (a command's ``--connect``).
        """
        env = os.environ

        def endpoints(name: str) -> tuple[str, ...] | None:
            raw = env.get(name)
            return None if raw is None else tuple(e for e in raw.split(",") if e)

        overrides: dict[str, Any] = {}
        if path := env.get("MOVER_ZENOH_CONFIG"):
            overrides = _read_overrides(path)
        mode = env.get("MOVER_MODE", "peer")
        listen = endpoints("MOVER_LISTEN")
        if listen is None:
            listen = () if mode == "client" else ("tcp/127.0.0.1:0",)
        return cls(
            mode=mode,
            listen=listen,
            connect=(endpoints("MOVER_CONNECT") or ()) + tuple(connect),
            overrides=overrides,
        )

    def env(self) -> dict[str, str]:
        """Environment variables that give a child process these settings."""
        return {
            "MOVER_MODE": self.mode,
            "MOVER_LISTEN": ",".join(self.listen),
            "MOVER_CONNECT": ",".join(self.connect),
        }

    def to_zenoh(self) -> zenoh.Config:
        """The zenoh configuration."""
        if self.mode not in ("peer", "client", "router"):
            raise ConfigError(f"bad zenoh mode {self.mode!r}: use peer, client or router")
        conf = zenoh.Config()
        settings: dict[str, Any] = {
            "mode": self.mode,
            "listen/endpoints": list(self.listen),
            "connect/endpoints": list(self.connect),
            "scouting/multicast/enabled": self.multicast,
            "transport/link/tx/lease": self.lease_ms,
            "transport/link/tx/keep_alive": self.keep_alive,
            # Retry quickly after a peer or router restart (docs/transport.md).
            "connect/retry": {"period_init_ms": 100, "period_max_ms": 500},
        }
        settings.update(self.overrides)
        for key, value in settings.items():
            try:
                conf.insert_json5(key, json.dumps(value))
            except Exception as exc:
                raise ConfigError(f"bad zenoh setting {key} = {value!r}: {exc}") from exc
        return conf


def _read_overrides(path: str) -> dict[str, Any]:
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read zenoh settings {path!r}: {exc}") from exc
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected an object of 'path/to/key': value settings")
    return data


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port that is free now (for tests and launchers)."""
    with socket.socket() as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])
