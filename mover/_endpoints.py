"""Zenoh endpoints (``tcp/127.0.0.1:7447``) read before zenoh sees them.

Zenoh refuses a bad endpoint only when the session opens (``zenoh.ZError: invalid port value``,
after whatever work came first); :func:`check_endpoint` says what is wrong in one line, naming
the option it came from, and :func:`beyond_loopback_in_clear` finds the endpoints that other
machines can reach without TLS. :func:`bound` names the port zenoh chose for ``:0``, and
:func:`join_hint` tells a process that waits for the team what to check and what to set.
"""

from __future__ import annotations

import contextlib
import ipaddress
import os
from collections.abc import Sequence

from ._exceptions import ConfigError

#: Protocols whose address is ``host:port`` (TLS and QUIC encrypt; the others do not).
_HOST_PORT = {"tcp", "udp", "tls", "quic", "ws"}
_ENCRYPTED = {"tls", "quic"}
#: Protocols zenoh knows whose address is something else (a path, a device): passed on as is.
_OTHER = {"unixsock-stream", "unixpipe", "serial", "vsock"}


def _split(endpoint: str) -> tuple[str, str]:
    """``(protocol, address)`` of an endpoint, metadata (``?...``) and config (``#...``) cut."""
    locator = endpoint.split("#", 1)[0].split("?", 1)[0]
    proto, sep, address = locator.partition("/")
    if not sep or not proto or not address:
        raise ConfigError(f"{endpoint!r}: not an endpoint (e.g. tcp/127.0.0.1:7447)")
    return proto, address


def _host_port(endpoint: str, address: str) -> tuple[str, int]:
    host, sep, port = address.rpartition(":")
    if not sep or not host:
        raise ConfigError(f"{endpoint!r}: needs host:port (e.g. tcp/127.0.0.1:7447)")
    if not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ConfigError(f"{endpoint!r}: the port must be from 0 to 65535, got {port!r}")
    if host.startswith("["):
        if not host.endswith("]"):
            raise ConfigError(f"{endpoint!r}: an IPv6 address goes in brackets: [::1]:7447")
        host = host[1:-1]
        try:
            ipaddress.IPv6Address(host)
        except ValueError:
            raise ConfigError(f"{endpoint!r}: {host!r} is not an IPv6 address") from None
    elif ":" in host:
        raise ConfigError(f"{endpoint!r}: an IPv6 address goes in brackets: [::1]:7447")
    return host, int(port)


def check_endpoint(endpoint: str, option: str = "endpoint") -> str:
    """``endpoint`` if zenoh can use it; else ConfigError naming ``option`` and what is wrong."""
    try:
        if not isinstance(endpoint, str):
            raise ConfigError(f"{endpoint!r}: not an endpoint (a string such as tcp/host:7447)")
        proto, address = _split(endpoint)
        if proto in _HOST_PORT:
            _host_port(endpoint, address)
        elif proto not in _OTHER:
            known = ", ".join(sorted(_HOST_PORT | _OTHER))
            raise ConfigError(f"{endpoint!r}: unknown protocol {proto!r} (one of {known})")
    except ConfigError as exc:
        raise ConfigError(f"{option} {exc}") from None
    return endpoint


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name: it may well resolve to a public address


def beyond_loopback_in_clear(endpoints: list[str]) -> list[str]:
    """The ones of ``endpoints`` (already checked) that other machines reach unencrypted."""
    found = []
    for endpoint in endpoints:
        proto, address = _split(endpoint)
        if proto in _HOST_PORT and proto not in _ENCRYPTED:
            host, _ = _host_port(endpoint, address)
            if not _is_loopback(host):
                found.append(endpoint)
    return found


def bound(endpoints: Sequence[str]) -> list[str]:
    """``endpoints`` (this process's listen endpoints, checked) as others can reach them: a TCP
    endpoint on port 0 gets the port this process listens on there (Linux: read from /proc);
    one whose port cannot be found is left out."""
    found = []
    listening = _listening()
    for endpoint in endpoints:
        proto, address = _split(endpoint)
        if proto != "tcp":
            found.append(endpoint)
            continue
        host, port = _host_port(endpoint, address)
        if port != 0:
            found.append(endpoint)
            continue
        ports = listening.get(host.strip("[]"), [])
        if ports:
            where = f"[{host}]" if ":" in host else host
            found.append(f"tcp/{where}:{ports.pop(0)}")
    return found


def _listening() -> dict[str, list[int]]:
    """This process's listening TCP sockets: address -> ports ({} where /proc cannot say)."""
    inodes = set()
    try:
        fds = os.listdir("/proc/self/fd")
    except OSError:
        return {}
    for fd in fds:
        with contextlib.suppress(OSError):
            target = os.readlink(f"/proc/self/fd/{fd}")
            if target.startswith("socket:["):
                inodes.add(target[8:-1])
    found: dict[str, list[int]] = {}
    for table in ("tcp", "tcp6"):
        try:
            with open(f"/proc/self/net/{table}") as f:
                rows = f.read().splitlines()[1:]
        except OSError:
            continue
        for row in rows:
            cells = row.split()
            if len(cells) < 10 or cells[3] != "0A" or cells[9] not in inodes:  # 0A: LISTEN
                continue
            address, port = cells[1].split(":")
            raw = bytes.fromhex(address)
            # /proc writes each 32-bit word of the address in the host's (little-endian) order
            words = b"".join(raw[i : i + 4][::-1] for i in range(0, len(raw), 4))
            found.setdefault(str(ipaddress.ip_address(words)), []).append(int(port, 16))
    return found


def join_hint(*, team: str, connect: Sequence[str], linked: bool, awaited: str) -> str:
    """What a process that waits for ``awaited`` (``"the world"``) of ``team`` should
    check, said plainly: the endpoints it connects to (``MOVER_CONNECT``), whether it reached
    anyone, and what to set."""
    fix = (
        f"set MOVER_CONNECT to the endpoint the READY line of {awaited} names, with its "
        "MOVER_TEAM and team key (MOVER_TEAM_KEY or MOVER_TEAM_KEY_FILE)"
    )
    if not connect and not linked:
        return f"this process connects to nothing (MOVER_CONNECT is not set) and no one came: {fix}"
    if not connect:
        return f"linked to no {awaited} yet (MOVER_CONNECT is not set): start it, or {fix}"
    where = ",".join(connect)
    if not linked:
        return (
            f"nothing answers at {where} (MOVER_CONNECT): is {awaited} (or its router) up? Or {fix}"
        )
    return (
        f"linked at {where} (MOVER_CONNECT), but {awaited} is not in team {team!r} there: start "
        "it, or check that MOVER_TEAM and the team key are the ones its READY line names (a "
        "process with another key is not seen)"
    )
