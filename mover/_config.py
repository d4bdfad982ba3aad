"""How a node reaches the others (NodeConfig) and which team it belongs to (TeamCredentials).

Default: zenoh peer mode on loopback, multicast scouting off, listening on a free port; peers
find each other by connecting to one or more known endpoints and zenoh's gossip links the rest.
Every process sets a short lease so a hung peer is noticed within about a second.

Environment (read by ``from_env``): ``MOVER_TEAM``, ``MOVER_TEAM_KEY`` (hex) or
``MOVER_TEAM_KEY_FILE``; ``MOVER_MODE`` (peer | client), ``MOVER_LISTEN`` and ``MOVER_CONNECT``
(comma-separated endpoints such as ``tcp/127.0.0.1:7447``), ``MOVER_ZENOH_CONFIG`` (a json5 file
merged over the defaults, e.g. TLS settings written by ``mover router --gen-config``).

Timeouts (read by ``from_env`` too; docs/transport.md and docs/network-lab.md say how the
defaults were measured): ``MOVER_PATIENCE`` (seconds a member that is unreachable but not known
dead stays *suspected* before it is lost; default 10), ``MOVER_LEASE_MS`` (a link silent this
long is closed and its members leave; default the patience), ``MOVER_KEEP_ALIVE``
(keep-alives sent per lease; default 10), ``MOVER_HELLO_TIMEOUT`` (seconds
one hello question waits for its answer; default 5), ``MOVER_HELLO_RETRIES`` (unanswered hellos
asked again, 0.2 s to 3 s apart; default 8) and ``MOVER_LEAVE_GRACE`` (seconds a member that left
may take to come back before what it held is given up; default 1).
"""

from __future__ import annotations

import json
import math
import os
import secrets
import socket
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import zenoh

from ._exceptions import ConfigError
from ._keys import check_name

MIN_KEY_BYTES = 16

# name: (environment variable, smallest, largest) of each timeout knob of NodeConfig
_KNOBS: dict[str, tuple[str, float, float]] = {
    "patience": ("MOVER_PATIENCE", 0.1, 3600.0),
    "lease_ms": ("MOVER_LEASE_MS", 100, 600_000),
    "keep_alive": ("MOVER_KEEP_ALIVE", 1, 100),
    "hello_timeout": ("MOVER_HELLO_TIMEOUT", 0.1, 600.0),
    "hello_retries": ("MOVER_HELLO_RETRIES", 0, 100),
    "leave_grace": ("MOVER_LEAVE_GRACE", 0.0, 600.0),
}
_INTEGRAL = {"lease_ms", "keep_alive", "hello_retries"}


@dataclass(frozen=True)
class TeamCredentials:
    """What a node needs to join a team: the team's name and its secret key (every envelope is
    sealed under keys derived from it). Who is in the team now is ``node.membership``; who runs
    a program together is a :class:`~mover.RunTeam`."""

    name: str
    key: bytes = field(repr=False)

    def __post_init__(self) -> None:
        check_name("team", self.name)
        if not isinstance(self.key, bytes) or len(self.key) < MIN_KEY_BYTES:
            raise ConfigError(f"a team key must be at least {MIN_KEY_BYTES} bytes")

    @classmethod
    def generate(cls, name: str) -> TeamCredentials:
        """A team with a fresh random 32-byte key."""
        return cls(name, secrets.token_bytes(32))

    @classmethod
    def from_env(cls, name: str | None = None) -> TeamCredentials:
        """The team named by ``MOVER_TEAM`` (or ``name``) with its key from the environment."""
        name = name or os.environ.get("MOVER_TEAM")
        if not name:
            raise ConfigError("no team: pass --team or set MOVER_TEAM")
        hexkey = os.environ.get("MOVER_TEAM_KEY")
        path = os.environ.get("MOVER_TEAM_KEY_FILE")
        if hexkey is None and path:
            try:
                hexkey = _read_text(path, 4096).strip()
            except (OSError, ValueError) as exc:
                raise ConfigError(f"cannot read MOVER_TEAM_KEY_FILE {path!r}: {exc}") from None
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
    """Zenoh settings and membership timeouts for one node.

    ``patience``: seconds a member that is unreachable but not known dead (a link that went
    silent: a partition, a stalled router, a long loss burst) is *suspected* and waited for
    before it is lost; a member whose process is known dead (its session closed: it exited or
    was killed, and its socket closed) is lost at once whatever the patience.
    ``lease_ms``: a zenoh link that hears nothing for this long is closed, and the members
    behind it leave; None (the default) makes it the patience, so that a link that comes back
    within the patience never closed (see docs/network-lab.md). ``keep_alive``: keep-alives per
    lease. ``hello_timeout``, ``hello_retries``: how
    long one hello question waits and how often an unanswered one is asked again before a token
    holder is given up as unverified. ``leave_grace``: how long a member that left may take to
    come back before what it held (its calls, its body in a world) is given up.
    """

    mode: str = "peer"
    listen: tuple[str, ...] = ("tcp/127.0.0.1:0",)
    connect: tuple[str, ...] = ()
    multicast: bool = False
    lease_ms: int | None = None
    keep_alive: int = 10
    overrides: dict[str, Any] = field(default_factory=dict)
    hello_timeout: float = 5.0
    hello_retries: int = 8
    leave_grace: float = 1.0
    patience: float = 10.0

    def __post_init__(self) -> None:
        for name, (_, low, high) in _KNOBS.items():
            value = getattr(self, name)
            integral = name in _INTEGRAL
            if value is None and name == "lease_ms":
                continue
            if (
                isinstance(value, bool)
                or not isinstance(value, int if integral else (int, float))
                or not math.isfinite(value)
                or not low <= value <= high
            ):
                kind = "an integer" if integral else "a number"
                raise ConfigError(f"{name} must be {kind} from {low} to {high}, not {value!r}")
        if self.lease / self.keep_alive < 10:
            every = f"{self.lease}/{self.keep_alive}"
            raise ConfigError(f"lease_ms / keep_alive must be at least 10 ms, not {every}")

    @property
    def lease(self) -> int:
        """The zenoh link lease in milliseconds: ``lease_ms``, else the patience."""
        return self.lease_ms if self.lease_ms is not None else round(self.patience * 1000)

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
            **_knobs_from_env(),
        )

    def env(self) -> dict[str, str]:
        """Environment variables that give a child process these settings (the timeouts only
        where they differ from the defaults, so that a parent's ``MOVER_*`` still reach it)."""
        env = {
            "MOVER_MODE": self.mode,
            "MOVER_LISTEN": ",".join(self.listen),
            "MOVER_CONNECT": ",".join(self.connect),
        }
        for name, (var, _, _) in _KNOBS.items():
            if getattr(self, name) != getattr(NodeConfig, name):
                env[var] = str(getattr(self, name))
        return env

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
            "transport/link/tx/lease": self.lease,
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


def _knobs_from_env() -> dict[str, Any]:
    """The timeout knobs set in the environment (ConfigError for one that is not a number)."""
    found: dict[str, Any] = {}
    for name, (var, low, high) in _KNOBS.items():
        raw = os.environ.get(var)
        if raw is None or not raw.strip():
            continue
        integral = name in _INTEGRAL
        try:
            value: float = int(raw) if integral else float(raw)
        except ValueError:
            kind = "an integer" if integral else "a number"
            raise ConfigError(f"${var} must be {kind} from {low} to {high}, not {raw!r}") from None
        if not (math.isfinite(value) and low <= value <= high):
            raise ConfigError(f"${var} must be from {low} to {high}, not {raw!r}")
        found[name] = value
    return found


def _read_text(path: str, limit: int) -> str:
    """The UTF-8 text of the file at ``path``; ValueError if it is over ``limit`` bytes (a
    path such as /dev/zero must not fill memory) or not UTF-8."""
    with open(path, "rb") as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise ValueError(f"larger than {limit} bytes")
    try:
        return data.decode()
    except UnicodeDecodeError as exc:
        raise ValueError(f"not UTF-8 text ({exc.reason})") from None


def _read_overrides(path: str) -> dict[str, Any]:
    try:
        data = json.loads(_read_text(path, 1 << 20))
    except RecursionError:
        raise ConfigError(f"cannot read zenoh settings {path!r}: nested too deeply") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read zenoh settings {path!r}: {exc}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected an object of 'path/to/key': value settings")
    return data


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port that is free now (for tests and launchers)."""
    with socket.socket() as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])
