"""Aseba Playground worlds of team files (``[world] kind = "playground"``): the file's robots,
their ports, and the world process's command line.

The Playground (``asebaplayground``, Debian package ``aseba``) simulates the Thymio IIs of a
``.playground`` file, each listening on its own TCP port. It is not a mover member: it has no
node, no membership and no lock-step; ``mover up`` starts it through ``mover playground``
(:mod:`robots.thymio.playground`), which prints :data:`READY` once every robot answers on its
port, and only then starts the robots, each with ``link=tcp:127.0.0.1:PORT`` of its name in the
file. Nothing here imports the robots' package.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Mapping

from .._config import free_port
from .._exceptions import ConfigError

PLAYGROUND = "asebaplayground"
"""The simulator's command."""
READY = "playground ready"
"""The line ``mover playground`` prints once every robot answers on its port."""
PORT_CHOICES = ("free", "file")
"""``free``: free ports, written into a temporary copy of the world file; ``file``: its own."""

_ROBOT = re.compile(r"<robot\b[^>]*>")
_ATTR = re.compile(r'\b(name|port)="([^"]*)"')


def world_robots(text: str) -> dict[str, int]:
    """The robots of a Playground world file's ``text``, name to TCP port, in the file's order;
    ValueError saying what is wrong (no robot, a robot without a name or a port, twice a name)."""
    found: dict[str, int] = {}
    for tag in _ROBOT.findall(text):
        attrs = dict(_ATTR.findall(tag))
        if "name" not in attrs or not attrs.get("port", "").isdigit():
            raise ValueError(f"a robot without name=... and port=...: {tag}")
        if attrs["name"] in found:
            raise ValueError(f"the robot name {attrs['name']!r} is given twice")
        found[attrs["name"]] = int(attrs["port"])
    if not found:
        raise ValueError('no <robot type="thymio2" ... port="..." name="..."/> in it')
    return found


def with_ports(text: str, ports: Mapping[str, int]) -> str:
    """The world file ``text`` with the robots of ``ports`` (by name) on those ports."""

    def one(m: re.Match[str]) -> str:
        tag = m.group(0)
        name = dict(_ATTR.findall(tag)).get("name", "")
        if name not in ports:
            return tag
        return re.sub(r'\bport="[^"]*"', f'port="{ports[name]}"', tag)

    return _ROBOT.sub(one, text)


def ports_of(robots: Mapping[str, int], choice: str) -> dict[str, int]:
    """Each robot's port in a run: the file's, or (``free``) a free one of this machine."""
    return dict(robots) if choice == "file" else {name: free_port() for name in robots}


def installed() -> None:
    """Raise ConfigError in one line when ``asebaplayground`` is not on PATH."""
    if shutil.which(PLAYGROUND) is None:
        raise ConfigError(
            f'[world] kind = "playground" needs {PLAYGROUND} on PATH '
            "(Debian package: aseba; `apt-get install aseba`)"
        )
