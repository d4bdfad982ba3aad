"""Endpoints read before zenoh sees them, and where ``mover router`` listens (no network)."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import pytest

from mover._endpoints import beyond_loopback_in_clear, check_endpoint
from mover._exceptions import ConfigError
from mover.cli._router import DEFAULT_LISTEN, listening

GOOD = [
    "tcp/127.0.0.1:7447",
    "tcp/0.0.0.0:0",
    "tls/10.0.0.5:7448",
    "udp/[::1]:7447",
    "tcp/robot.local:65535",
    "tcp/127.0.0.1:7447?prio=1#iface=lo",
    "unixsock-stream//tmp/zenoh.sock",
]
BAD = {
    "tcp/127.0.0.1:99999": "the port must be from 0 to 65535, got '99999'",
    "tcp/127.0.0.1:-1": "the port must be",
    "tcp/127.0.0.1": "needs host:port",
    "tcp/:7447": "needs host:port",
    "tcp/::1:7447": "in brackets",
    "tcp/[nonsense]:7447": "is not an IPv6 address",
    "garbage": "not an endpoint",
    "tcp/": "not an endpoint",
    "http/127.0.0.1:80": "unknown protocol 'http'",
}


@pytest.mark.parametrize("endpoint", GOOD)
def test_a_good_endpoint_passes(endpoint: str) -> None:
    assert check_endpoint(endpoint) == endpoint


@pytest.mark.parametrize(("endpoint", "said"), BAD.items())
def test_a_bad_endpoint_is_one_line_naming_its_option(endpoint: str, said: str) -> None:
    with pytest.raises(ConfigError) as caught:
        check_endpoint(endpoint, "--listen")
    assert str(caught.value).startswith(f"--listen {endpoint!r}: ")
    assert said in str(caught.value)


def test_what_other_machines_reach_in_clear() -> None:
    endpoints = [
        "tcp/127.0.0.1:7447",
        "tcp/localhost:7447",
        "udp/[::1]:7447",
        "tcp/0.0.0.0:7447",
        "tcp/[::]:7447",
        "ws/10.0.0.5:80",
        "tcp/robot.local:7447",
        "tls/0.0.0.0:7448",
        "quic/0.0.0.0:7448",
        "unixsock-stream//tmp/z.sock",
    ]
    assert beyond_loopback_in_clear(endpoints) == [
        "tcp/0.0.0.0:7447",
        "tcp/[::]:7447",
        "ws/10.0.0.5:80",
        "tcp/robot.local:7447",
    ]


def _args(*listen: str, config: str | None = None) -> argparse.Namespace:
    return argparse.Namespace(listen=list(listen) or None, config=config)


def test_a_router_without_settings_listens_on_this_machine_only_and_says_how_to_widen() -> None:
    config, notes = listening(_args())
    assert config.listen == (DEFAULT_LISTEN,) == ("tcp/127.0.0.1:7447",)
    assert len(notes) == 1 and "this machine only (--listen tcp/0.0.0.0:7447" in notes[0]


def test_listening_wider_in_clear_is_one_warning() -> None:
    _, notes = listening(_args("tcp/0.0.0.0:7447", "tcp/192.168.1.2:7447"))
    assert notes == [
        "warning: tcp/0.0.0.0:7447, tcp/192.168.1.2:7447 can be reached from other machines "
        "without TLS: anyone there can join the network (mover router --gen-config writes "
        "TLS and an ACL)"
    ]
    assert listening(_args("tls/0.0.0.0:7448"))[1] == []
    assert listening(_args("tcp/127.0.0.1:7000"))[1] == []


def test_a_config_file_s_endpoints_are_checked_and_warned_of(tmp_path: Path) -> None:
    path = tmp_path / "router.json"
    path.write_text(json.dumps({"listen/endpoints": ["tcp/0.0.0.0:7447"]}))
    config, notes = listening(_args(config=str(path)))
    assert config.listen == () and len(notes) == 1 and notes[0].startswith("warning: tcp/0.0.0.0")
    path.write_text(json.dumps({"listen/endpoints": ["tcp/0.0.0.0:99999"]}))
    said = re.escape("router.json: listen/endpoints 'tcp/0.0.0.0:99999'")
    with pytest.raises(ConfigError, match=said):
        listening(_args(config=str(path)))
