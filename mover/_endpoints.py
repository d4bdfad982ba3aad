"""Zenoh endpoints (``tcp/127.0.0.1:7447``) read before zenoh sees them.

Zenoh refuses a bad endpoint only when the session opens (``zenoh.ZError: invalid port value``,
after whatever work came first); :func:`check_endpoint` says what is wrong in one line, naming
the option it came from, and :func:`beyond_loopback_in_clear` finds the endpoints that other
machines can reach without TLS.
"""

from __future__ import annotations

import ipaddress

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
