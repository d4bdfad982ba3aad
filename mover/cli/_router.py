"""`mover router`: a zenoh router for multi-machine teams, and the config to secure it.

A router is a Python zenoh session in router mode (no separate binary). ``--gen-config DIR``
writes, for one team, a certificate authority, a router certificate, one client certificate per
member (common name = member name) and per workstation (``--workstations``: tools such as
``mover run``), ``router.json`` (TLS listener with a bounded handshake, mutual TLS, and the
per-member access-control list of :mod:`._acl`: only ``<name>``'s certificate serves
``<name>``'s keys) and ``member-<name>.json`` for each (client mode, connecting over mutual
TLS). A process uses its file through ``MOVER_ZENOH_CONFIG``; the team key (envelope
signatures) still applies on top, so a member whose certificate leaks still cannot forge team
messages (docs/security.md).

An ACL applies only in the node that has it (docs/transport.md). Robots behind the router should
run as clients (``MOVER_MODE=client``) and listen on nothing, so that no outsider can link to them
directly and bypass the router.
"""

from __future__ import annotations

import argparse
import datetime
import ipaddress
import json
import os
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._config import NodeConfig, _knobs_from_env, _read_overrides
from .._endpoints import beyond_loopback_in_clear, check_endpoint
from .._exceptions import ConfigError
from .._keys import check_name
from . import add_command
from ._acl import team_acl

DEFAULT_LISTEN = "tcp/127.0.0.1:7447"
"""Where a router without ``--listen`` or a config listens: this machine only."""
WIDE_LISTEN = "tcp/0.0.0.0:7447"

CLOSE_BOUND = 10.0
"""Seconds a stopping router may take to close its session before it exits anyway."""

HANDSHAKE_TIMEOUT_MS = 1000
"""Milliseconds the router gives a connection to finish its TLS handshake (zenoh's default is
10 s): an idle connection is let go this soon. It does not bound starvation by idle
connections: zenoh's TLS accept loop sleeps 100 ms after every failed handshake (a constant,
no setting), so 1000 idle ones hold back a new member for about 100 s whatever this is;
docs/security.md has the measurement and the operator's remedy (a per-source limit)."""
TRANSPORT = {
    "accept_timeout": 2000,  # zenoh's own handshake after TLS (default 10 s)
    "accept_pending": 100,  # links in that handshake at once (zenoh's default)
    "open_timeout": 10000,  # a member opening a link: long enough to wait out a queue
}
"""``transport/unicast`` settings written to the router's and the members' configs."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``router`` verb."""
    p = add_command(
        sub,
        "router",
        run,
        "run a zenoh router, or write a secured config for one",
        __doc__.split("\n\n")[0],
    )
    p.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help=f"endpoint to listen on (default {DEFAULT_LISTEN}: this machine only; "
        f"{WIDE_LISTEN} for every interface); repeatable",
    )
    p.add_argument("--config", metavar="FILE", help="a JSON settings file (e.g. router.json)")
    p.add_argument("--gen-config", metavar="DIR", help="write certificates and configs to DIR")
    p.add_argument("--team", help="team name (with --gen-config)")
    p.add_argument(
        "--members",
        help="comma-separated names of the processes that serve a name of their own: robots, "
        "worlds, workstation groups (with --gen-config)",
    )
    p.add_argument(
        "--workstations",
        default="",
        help="comma-separated certificate names for tools (mover run, mover ps: fresh names, "
        "never a member's) (with --gen-config)",
    )
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="router address the members connect to (with --gen-config)",
    )
    p.add_argument("--port", type=int, default=7448, help="TLS port (with --gen-config)")


def run(args: argparse.Namespace) -> int:
    from . import UsageError

    if args.gen_config:
        if not args.team or not args.members:
            raise UsageError("--gen-config needs --team and --members")
        try:
            check_name("team", args.team)
            members = [check_name("member", m) for m in args.members.split(",") if m]
            tools = [check_name("workstation", m) for m in args.workstations.split(",") if m]
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        if not 1 <= args.port <= 65535:
            raise UsageError(f"--port must be from 1 to 65535, got {args.port}")
        target = Path(args.gen_config)
        if target.exists() and not target.is_dir():
            raise UsageError(f"--gen-config {target}: exists and is not a directory")
        try:
            written = generate_config(target, args.team, members, args.host, args.port, tools)
        except OSError as exc:
            raise UsageError(f"--gen-config {target}: {exc.strerror or exc}") from None
        for path in written:
            print(path)
        return 0
    config, notes = listening(args)
    for line in notes:
        print(f"mover router: {line}", file=sys.stderr)
    serve(config)
    return 0


def listening(args: argparse.Namespace) -> tuple[NodeConfig, list[str]]:
    """The router's settings from ``--listen`` and ``--config`` (every endpoint checked before
    zenoh sees it), and what to tell the user first: where a router without either listens
    (this machine only) and one warning if other machines reach it without TLS."""
    from . import UsageError

    overrides: dict[str, Any] = {}
    if args.config:
        try:
            overrides = _read_overrides(args.config)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    notes = []
    listen = tuple(check_endpoint(e, "--listen") for e in args.listen or ())
    effective = list(listen)
    if "listen/endpoints" in overrides:  # the file's endpoints replace --listen's
        effective = overrides["listen/endpoints"]
        if not isinstance(effective, list):
            effective = []  # zenoh's per-mode form ({"router": [...]}): zenoh checks it
        for endpoint in effective:
            check_endpoint(endpoint, f"{args.config}: listen/endpoints")
    elif not listen:
        listen = (DEFAULT_LISTEN,)
        effective = list(listen)
        notes.append(
            f"listening on {DEFAULT_LISTEN}, this machine only (--listen {WIDE_LISTEN} for "
            "every interface; --gen-config for TLS and an ACL)"
        )
    clear = beyond_loopback_in_clear(effective)
    if clear:
        notes.append(
            f"warning: {', '.join(clear)} can be reached from other machines without TLS: "
            "anyone there can join the network (mover router --gen-config writes TLS and an ACL)"
        )
    # the team's patience and timeouts ($MOVER_PATIENCE...): the members' links to the router
    # last as long as theirs to each other
    config = NodeConfig(mode="router", listen=listen, overrides=overrides, **_knobs_from_env())
    return config, notes


def serve(config: NodeConfig) -> None:
    """Run a router until SIGINT or SIGTERM."""
    import zenoh

    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    where = ", ".join(config.listen) or "the config's endpoints"
    try:
        session = zenoh.open(config.to_zenoh())
    except zenoh.ZError as exc:  # the port is taken, the address is not this machine's...
        raise ConfigError(f"cannot listen on {where}: {exc}") from None
    with session:
        print(f"router {session.zid()} listening on {where}", flush=True)
        stop.wait()
        # Closing waits on zenoh's links; bounded, so that a stop never hangs (a test saw a
        # router outlive its SIGTERM for two minutes on a loaded machine, once).
        watchdog = threading.Timer(CLOSE_BOUND, _exit_now)
        watchdog.daemon = True
        watchdog.start()


def _exit_now() -> None:
    print(f"router: closing took over {CLOSE_BOUND:g} s: exiting", file=sys.stderr, flush=True)
    os._exit(0)


def generate_config(
    directory: Path,
    team: str,
    members: list[str],
    host: str,
    port: int,
    tools: Sequence[str] = (),
) -> list[Path]:
    """Write a CA, certificates and router/member configs for ``team``; return the files.

    One certificate per name of ``members`` (common name = the name: the processes that serve
    that name, robots, worlds, workstation groups) and of ``tools`` (workstations running
    ``mover run``, ``mover ps``: processes with fresh names). The ACL is :func:`team_acl`'s."""
    tools = [t for t in tools if t not in members]
    directory.mkdir(parents=True, exist_ok=True)
    ca_key, ca_cert = _certificate(f"mover {team} CA", None, host, ca=True)
    files = {"ca.pem": _pem(ca_cert)}
    r_key, r_cert = _certificate("router", (ca_key, ca_cert), host)
    files["router-cert.pem"], files["router-key.pem"] = _pem(r_cert), _pem(r_key)
    for member in [*members, *tools]:
        m_key, m_cert = _certificate(member, (ca_key, ca_cert), host)
        files[f"{member}-cert.pem"], files[f"{member}-key.pem"] = _pem(m_cert), _pem(m_key)
    written = []
    for name, data in files.items():
        path = directory / name
        path.write_bytes(data)
        if name.endswith("-key.pem"):
            path.chmod(0o600)
        written.append(path)
    d = directory.resolve()
    router = {
        "listen/endpoints": [router_endpoint(host, port)],
        "transport/link/tls": {
            "root_ca_certificate": str(d / "ca.pem"),
            "listen_certificate": str(d / "router-cert.pem"),
            "listen_private_key": str(d / "router-key.pem"),
            "enable_mtls": True,
        },
        "transport/unicast": dict(TRANSPORT),
        "access_control": team_acl(team, members, tools),
    }
    (directory / "router.json").write_text(json.dumps(router, indent=2))
    written.append(directory / "router.json")
    for member in [*members, *tools]:
        client = {
            "connect/endpoints": [f"tls/{host}:{port}"],
            "listen/endpoints": [],
            "transport/link/tls": {
                "root_ca_certificate": str(d / "ca.pem"),
                "connect_certificate": str(d / f"{member}-cert.pem"),
                "connect_private_key": str(d / f"{member}-key.pem"),
                "enable_mtls": True,
            },
            "transport/unicast": dict(TRANSPORT),
        }
        path = directory / f"member-{member}.json"
        path.write_text(json.dumps(client, indent=2))
        written.append(path)
    return written


def router_endpoint(host: str, port: int) -> str:
    """The router's TLS endpoint, with its handshake bound (:data:`HANDSHAKE_TIMEOUT_MS`)."""
    where = f"[{host}]" if ":" in host else host
    return f"tls/{where}:{port}#tls_handshake_timeout_ms={HANDSHAKE_TIMEOUT_MS}"


def _certificate(
    common_name: str, issuer: tuple[Any, Any] | None, host: str, ca: bool = False
) -> tuple[Any, Any]:
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, common_name)])
    issuer_key, issuer_cert = issuer if issuer else (key, None)
    now = datetime.datetime.now(datetime.UTC)
    try:
        alt: x509.GeneralName = x509.IPAddress(ipaddress.ip_address(host))
    except ValueError:
        alt = x509.DNSName(host)
    builder = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(issuer_cert.subject if issuer_cert else name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=365))
        .add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True)
    )
    if not ca:
        builder = builder.add_extension(
            x509.SubjectAlternativeName([alt, x509.DNSName("localhost")]), critical=False
        )
    return key, builder.sign(issuer_key, hashes.SHA256())


def _pem(obj: Any) -> bytes:
    from cryptography.hazmat.primitives import serialization

    if hasattr(obj, "private_bytes"):
        return bytes(
            obj.private_bytes(
                serialization.Encoding.PEM,
                serialization.PrivateFormat.PKCS8,
                serialization.NoEncryption(),
            )
        )
    return bytes(obj.public_bytes(serialization.Encoding.PEM))
