"""Teams across hosts: which machine runs what, and how its processes reach the others.

A team file's ``[[hosts]]`` names the machines (``name``, ``address``: where the others reach
it, ``port``: its router's, default 7448, ``router = true`` on the one that runs the router;
default the first); the world and each group say ``host = "..."`` (default the router's
host). ``mover up TEAM.toml --host NAME`` starts NAME's part: the router if it is the router's
host, the world if it is there, its groups; every process, and ``mover up`` itself (member
``up-NAME``), is a client of the one router, so readiness is membership across hosts.

With ``[team] tls = "DIR"`` (written by ``mover up TEAM.toml --gen-config DIR``: one
certificate per process of the file, per host's ``up-NAME`` and for ``workstation`` tools such
as ``mover run``, the router's config with the per-member ACL of :mod:`mover.cli._acl`) every
link is mutual TLS; without it, plain TCP (``mover router`` warns once). The team key must be
the same on every host: ``key_file`` or ``MOVER_TEAM_KEY``/``MOVER_TEAM_KEY_FILE``.
"""

from __future__ import annotations

import ipaddress
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from .._config import NodeConfig
from .._exceptions import ConfigError
from .._keylines import Path as KeyPath
from .._tables import BOOLEAN, NAME, STRING, Kind, Table, Wrong, hint, integer

if TYPE_CHECKING:
    from ._teamfile import TeamPlan

MAX_HOSTS = 64
"""The most hosts a team file may name."""
ROUTER_PORT = 7448
"""The router's port when a host does not say."""
WORKSTATION = "workstation"
"""The certificate ``--gen-config`` writes for tools (``mover run``, ``mover ps``)."""


@dataclass(frozen=True)
class HostPlan:
    """One machine of a team across hosts."""

    name: str
    address: str
    port: int = ROUTER_PORT
    router: bool = False


_HOSTNAME = re.compile(r"[A-Za-z0-9]([A-Za-z0-9.-]{0,251}[A-Za-z0-9])?\Z")


def _address(value: object) -> str:
    text = STRING.check(value)
    try:
        ipaddress.ip_address(text)
    except ValueError:
        if not _HOSTNAME.match(text):
            raise Wrong(f"must be a host name or an IP address, got {text!r}") from None
    return text


_ADDRESS = Kind("a host name or IP address", _address)


def read_hosts(root: Table) -> tuple[HostPlan, ...]:
    """The file's ``[[hosts]]`` (() if none); exactly one runs the router (default the first)."""
    found: list[HostPlan] = []
    for t in root.tables("hosts", most=MAX_HOSTS):
        t.only(("name", "address", "port", "router"))
        host = HostPlan(
            name=t.read("name", NAME),
            address=t.read("address", _ADDRESS),
            port=t.read("port", integer(low=1, high=65535), ROUTER_PORT),
            router=t.read("router", BOOLEAN, False),
        )
        if any(h.name == host.name for h in found):
            raise t.fail("name", f"{host.name!r} is listed twice")
        if host.router and any(h.router for h in found):
            raise t.fail("router", "only one host runs the router")
        found.append(host)
    if found and not any(h.router for h in found):
        found[0] = replace(found[0], router=True)
    return tuple(found)


def placed(plan: TeamPlan, root: Table) -> TeamPlan:
    """``plan`` with every process on a host of the file (the router's when it names none);
    a host that is not listed, or a host without ``[[hosts]]``, is refused at its line."""
    names = [h.name for h in plan.hosts]
    wheres: list[tuple[KeyPath, object]] = [
        (("world", "host"), plan.world.host if plan.world else None)
    ]
    groups = [t for s in ("robots", "workstations") for t in root.tables(s, most=10**6)]
    for g in groups:
        wheres.append(((*g.path, "host"), g.data.get("host")))
    for path, host in wheres:
        if host is None:
            continue
        if not names:
            raise root.fail(path, f"names host {host!r} but the file has no [[hosts]]")
        if host not in names:
            raise root.fail(path, f"{host!r} is no host of [[hosts]]{hint(str(host), names)}")
    if plan.tls is not None and not names:
        raise root.fail(("team", "tls"), "is for a team across hosts: add [[hosts]]")
    if not names:
        return plan
    if plan.topology == "peer":
        raise root.fail(("team", "topology"), "a team across hosts runs through a router")
    home = router_host(plan).name
    world = replace(plan.world, host=plan.world.host or home) if plan.world else None
    members = tuple(replace(m, host=m.host or home) for m in plan.members)
    return replace(plan, world=world, members=members, topology="router")


def router_host(plan: TeamPlan) -> HostPlan:
    """The host that runs the router."""
    return next(h for h in plan.hosts if h.router)


def host_of(plan: TeamPlan, name: str) -> HostPlan:
    """The host called ``name``; ConfigError naming the file's hosts if there is none."""
    for h in plan.hosts:
        if h.name == name:
            return h
    names = [h.name for h in plan.hosts]
    if not names:
        raise ConfigError(f"--host {name}: {plan.source} has no [[hosts]]")
    raise ConfigError(f"--host {name}: no such host in {plan.source}{hint(name, names)}")


def endpoint(plan: TeamPlan) -> str:
    """Where every process of a team across hosts connects: the router."""
    r = router_host(plan)
    where = f"[{r.address}]" if ":" in r.address else r.address
    return f"{'tls' if plan.tls else 'tcp'}/{where}:{r.port}"


def supervisor(host: str) -> str:
    """The member name of ``mover up --host HOST`` itself."""
    return f"up-{host}"


def certificate_names(plan: TeamPlan) -> list[str]:
    """Every name that serves keys of its own: the world, the groups, each host's ``mover up``."""
    names = [plan.world.name] if plan.world else []
    return names + [m.name for m in plan.members] + [supervisor(h.name) for h in plan.hosts]


def member_config(plan: TeamPlan, name: str) -> NodeConfig:
    """How the process ``name`` of a team across hosts reaches the team: a client of the
    router (over mutual TLS with its own certificate, when the file has ``tls``)."""
    if plan.tls is None:
        return NodeConfig(mode="client", listen=(), connect=(endpoint(plan),))
    from .._config import _read_overrides

    return NodeConfig(
        mode="client", listen=(), overrides=_read_overrides(str(tls_file(plan, name)))
    )


def member_env(plan: TeamPlan, name: str) -> dict[str, str]:
    """The environment that gives the process ``name`` its :func:`member_config`."""
    config = member_config(plan, name)
    env = config.env()
    if plan.tls is not None:
        env["MOVER_ZENOH_CONFIG"] = str(tls_file(plan, name))
    return env


def tls_file(plan: TeamPlan, name: str) -> Path:
    """The member config ``--gen-config`` wrote for ``name``; ConfigError if it is missing."""
    assert plan.tls is not None
    path = plan.tls / f"member-{name}.json"
    if not path.is_file():
        raise ConfigError(
            f"{path}: missing (write the certificates with mover up {plan.source} --gen-config "
            f"{plan.tls}, and copy the folder to every host)"
        )
    return path


def router_args(plan: TeamPlan) -> list[str]:
    """``mover router``'s arguments on the router's host."""
    if plan.tls is not None:
        config = plan.tls / "router.json"
        if not config.is_file():
            raise ConfigError(f"{config}: missing (mover up {plan.source} --gen-config {plan.tls})")
        return ["router", "--config", str(config)]
    r = router_host(plan)
    where = f"[{r.address}]" if ":" in r.address else r.address
    return ["router", "--listen", f"tcp/{where}:{r.port}"]


def generate(plan: TeamPlan, directory: Path) -> list[Path]:
    """Write the certificates and configs of ``plan``'s team (see the module docstring)."""
    from ..cli._router import generate_config

    if not plan.hosts:
        raise ConfigError(f"--gen-config: {plan.source} has no [[hosts]]")
    r = router_host(plan)
    names = certificate_names(plan)
    return generate_config(directory, plan.name, names, r.address, r.port, [WORKSTATION])
