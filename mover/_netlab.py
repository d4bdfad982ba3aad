"""Several hosts on one Linux machine: network namespaces on a bridge, for tests across a network.

::

    async with Netlab(("a", "b", "c")) as lab:
        router = await lab.start("a", [sys.executable, "-m", "mover._cli", "router", ...])
        robot = await lab.start("b", [...], env=env)      # reaches a at lab["a"].address
        async with lab.partition("b", 5.0): ...            # b's cable out for 5 s

Each host is a network namespace with one interface, ``eth0``, at ``10.77.0.<n>/24`` (the first
host .1), cabled by a veth pair to a bridge that only this lab's hosts are on: no address in the
machine's own namespace, no route out, so traffic goes only between the lab's hosts, and two
labs (parallel tests) never see each other even with the same subnet. A partition sets a host's
cable down at the bridge end (:meth:`Netlab.link`): the host's interface keeps its address and
routes (no carrier), so its sockets see silence, not an error, like a radio out of range.

Every name the lab makes begins with a tag of its own, ``mvl<pid in hex><n>``: namespaces
``<tag>-<host>``, links ``<tag><host>`` and the bridge ``<tag>br``. Closing (on leaving the
``async with``, an exception, Ctrl-C; again at interpreter exit; :meth:`Netlab.close` is
idempotent) kills every process in the lab's namespaces, whoever started it, then deletes the
namespaces, links and bridge. What a SIGKILLed lab left behind is removed by :func:`sweep`, run
whenever a lab opens: names with a tag whose process is gone.

Needs root, ``ip`` (iproute2) with network namespaces: :func:`unavailable` says why not.
Linux only. Processes run with ``ip netns exec``; an in-process socket is made in a host with
:meth:`Netlab.socket` (the proxy of :mod:`mover._impair` listens in a host that way).
"""

from __future__ import annotations

import asyncio
import atexit
import contextlib
import ctypes
import itertools
import os
import re
import shutil
import signal
import socket
import subprocess
import threading
import time
import weakref
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import IO

from ._procs import Child, start, stop

__all__ = ["Host", "Netlab", "NetlabError", "sweep", "unavailable"]

PREFIX = "mvl"
"""The first letters of every name a lab makes (then the owner's pid in hex, and its number)."""
SUBNET = "10.77.0"
"""The lab's /24: host n (from 1) is ``SUBNET.n``. Only the lab's hosts are on it."""
IP_TIMEOUT = 10.0
"""Seconds one ``ip`` command may take."""
KILL_WAIT = 5.0
"""Seconds closing waits for the processes of a namespace to be gone before deleting it."""
_HOST_NAME = re.compile(r"[a-z][a-z0-9]{0,4}\Z")
_TAG = re.compile(PREFIX + r"([0-9a-f]{6})([0-9a-z])")
_CLONE_NEWNET = 0x40000000
_labs: weakref.WeakSet[Netlab] = weakref.WeakSet()
_numbers = itertools.count()


class NetlabError(Exception):
    """The lab could not be built or changed: the ``ip`` command and what it said."""


@dataclass(frozen=True)
class Host:
    """One host of a lab: its name, its namespace, its address and its cable (the bridge end)."""

    name: str
    ns: str
    address: str
    link: str


def unavailable() -> str | None:
    """Why a lab cannot be built here (None: it can): not Linux, not root, no ``ip``, or no
    network namespaces."""
    if not os.path.exists("/proc/self/ns/net"):
        return "no network namespaces (Linux only)"
    if os.geteuid() != 0:
        return "network namespaces need root"
    if shutil.which("ip") is None:
        return "no `ip` command (Debian: apt-get install iproute2)"
    try:
        _ip("netns", "list")
    except NetlabError as exc:
        return f"`ip netns` does not work here: {exc}"
    return None


def _ip(*args: str, check: bool = True) -> str:
    """Run ``ip ARGS``; its output. NetlabError (with ``check``) if it fails."""
    try:
        done = subprocess.run(
            ["ip", *args], capture_output=True, text=True, timeout=IP_TIMEOUT, check=False
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise NetlabError(f"ip {' '.join(args)}: {exc}") from None
    if check and done.returncode != 0:
        raise NetlabError(f"ip {' '.join(args)}: {done.stderr.strip() or done.returncode}")
    return done.stdout


def _ip_path() -> str:
    return shutil.which("ip") or "/usr/sbin/ip"


def _namespaces() -> list[str]:
    return [line.split()[0] for line in _ip("netns", "list", check=False).splitlines() if line]


def _links() -> list[str]:
    names = []
    for line in _ip("-o", "link", "show", check=False).splitlines():
        parts = line.split(":", 2)
        if len(parts) > 1:
            names.append(parts[1].strip().split("@")[0])
    return names


def _ns_pids(ns: str) -> list[int]:
    return [int(p) for p in _ip("netns", "pids", ns, check=False).split() if p.isdigit()]


def _kill_namespace(ns: str) -> None:
    """Kill every process in ``ns`` (waiting up to ``KILL_WAIT`` s for them to go), then
    delete it. A stopped process is continued, so that it can die."""
    deadline = time.monotonic() + KILL_WAIT
    while pids := [p for p in _ns_pids(ns) if p != os.getpid()]:
        for pid in pids:
            for sig in (signal.SIGKILL, signal.SIGCONT):
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.kill(pid, sig)
        if time.monotonic() > deadline:
            break
        time.sleep(0.02)
    _ip("netns", "del", ns, check=False)


def _owner_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def sweep(*, all_tags: bool = False) -> list[str]:
    """Remove what labs whose process is gone left behind (a SIGKILLed test run): namespaces,
    with their processes, and links whose names carry a lab tag. ``all_tags`` removes those of
    live labs too (the command line's ``--sweep``, when nothing should be running). The names
    removed."""
    live = {lab.tag for lab in _labs if not lab.closed}

    def stale(name: str) -> bool:
        m = _TAG.match(name)
        if m is None or name[: m.end()] in live:
            return False
        return all_tags or not _owner_alive(int(m.group(1), 16))

    removed = []
    for ns in _namespaces():
        if stale(ns):
            _kill_namespace(ns)
            removed.append(ns)
    for link in _links():
        if stale(link):
            _ip("link", "del", link, check=False)
            removed.append(link)
    return removed


def _setns(fd: int) -> None:
    if hasattr(os, "setns"):  # Python 3.12
        os.setns(fd, _CLONE_NEWNET)
        return
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.setns(fd, _CLONE_NEWNET) != 0:
        err = ctypes.get_errno()
        raise OSError(err, os.strerror(err))


def socket_in(
    ns: str, family: int = socket.AF_INET, kind: int = socket.SOCK_STREAM
) -> socket.socket:
    """A new socket in network namespace ``ns`` (it binds, listens and connects there, whatever
    namespace uses it). Made on a thread of its own, which enters ``ns`` and dies after."""
    made: list[socket.socket] = []
    failed: list[BaseException] = []

    def work() -> None:
        try:
            with (
                open("/proc/thread-self/ns/net", "rb") as own,
                open(f"/run/netns/{ns}", "rb") as it,
            ):
                _setns(it.fileno())
                try:
                    made.append(socket.socket(family, kind))
                finally:
                    _setns(own.fileno())  # if this fails the thread ends anyway
        except BaseException as exc:
            failed.append(exc)

    thread = threading.Thread(target=work, name=f"netns {ns}", daemon=True)
    thread.start()
    thread.join()
    if failed:
        raise failed[0]
    return made[0]


class Netlab:
    """Hosts ``names`` (each 1 to 5 lower-case letters or digits, the first a letter) on one
    bridge. ``async with`` builds them and tears everything down; :meth:`open` and
    :meth:`close` do the same without it."""

    def __init__(self, names: Sequence[str] = ("a", "b", "c"), *, subnet: str = SUBNET) -> None:
        if not names or len(set(names)) != len(names) or len(names) > 250:
            raise ValueError(f"a lab needs 1 to 250 distinct host names, not {list(names)}")
        for n in names:
            if not _HOST_NAME.match(n):
                raise ValueError(f"host name {n!r}: 1 to 5 lower-case letters or digits")
        number = next(_numbers) % 36
        self.tag = f"{PREFIX}{os.getpid():06x}{'0123456789abcdefghijklmnopqrstuvwxyz'[number]}"
        self.bridge = f"{self.tag}br"
        self.hosts = {
            n: Host(n, f"{self.tag}-{n}", f"{subnet}.{i}", f"{self.tag}{n}")
            for i, n in enumerate(names, 1)
        }
        self.children: list[Child] = []
        self.opened = False
        self.closed = False

    def __getitem__(self, name: str) -> Host:
        return self.hosts[name]

    # -- building and tearing down -------------------------------------------------------------

    def open(self) -> None:
        """Build the bridge and the hosts (after a :func:`sweep` of stale labs). NetlabError
        if ``ip`` refuses; whatever was built by then is torn down."""
        if self.opened:
            return
        if reason := unavailable():
            raise NetlabError(reason)
        sweep()
        self.opened = True
        _labs.add(self)
        try:
            _ip("link", "add", self.bridge, "type", "bridge")
            _ip("link", "set", self.bridge, "up")
            for h in self.hosts.values():
                _ip("netns", "add", h.ns)
                _ip("link", "add", h.link, "type", "veth", "peer", "name", "eth0", "netns", h.ns)
                _ip("link", "set", h.link, "master", self.bridge, "up")
                _ip("-n", h.ns, "addr", "add", f"{h.address}/24", "dev", "eth0")
                _ip("-n", h.ns, "link", "set", "eth0", "up")
                _ip("-n", h.ns, "link", "set", "lo", "up")
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        """Kill every process in the lab's namespaces and delete the namespaces, the cables and
        the bridge. Idempotent; never raises for what is already gone."""
        if self.closed or not self.opened:
            self.closed = True
            return
        self.closed = True
        for c in self.children:
            c.signal(signal.SIGCONT)
            c.signal(signal.SIGKILL)
        for h in self.hosts.values():
            _kill_namespace(h.ns)
        links = set(_links())
        for name in [h.link for h in self.hosts.values()] + [self.bridge]:
            if name in links:
                _ip("link", "del", name, check=False)

    async def aclose(self) -> None:
        """:meth:`close`, then wait (briefly) for the lab's children to be reaped."""
        self.close()
        if self.children:
            await stop(self.children, [(signal.SIGKILL, KILL_WAIT)])

    async def __aenter__(self) -> Netlab:
        self.open()
        return self

    async def __aexit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.aclose()

    def leftovers(self) -> list[str]:
        """The lab's namespaces and links that exist now (none once it is closed)."""
        return [n for n in _namespaces() + _links() if n.startswith(self.tag)]

    # -- processes -----------------------------------------------------------------------------

    async def start(
        self,
        host: str,
        argv: Sequence[str],
        *,
        env: dict[str, str] | None = None,
        log: IO[bytes] | None = None,
        pump: bool = False,
        cwd: Path | None = None,
        label: str | None = None,
    ) -> Child:
        """Start ``argv`` in ``host`` (``ip netns exec``), in a session of its own, dying with
        this process (:func:`mover._procs.start`: ``log``, ``pump``). Its standard output is a
        pipe. Killed when the lab closes."""
        ns = self.hosts[host].ns
        child = await start(
            label or f"{host}: {' '.join(argv)[:50]}",
            [_ip_path(), "netns", "exec", ns, *argv],
            env=dict(os.environ if env is None else env),
            log=log,
            pump=pump,
            cwd=cwd,
            own_session=True,
        )  # fmt: skip
        self.children.append(child)
        return child

    async def run(
        self, host: str, *argv: str, timeout: float = 30.0, env: dict[str, str] | None = None
    ) -> tuple[int, str]:
        """Run ``argv`` in ``host`` to its end; its exit code and its output (with its standard
        error). Killed after ``timeout`` s (TimeoutError)."""
        proc = await asyncio.create_subprocess_exec(
            _ip_path(), "netns", "exec", self.hosts[host].ns, *argv,
            env=env, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT,
        )  # fmt: skip
        try:
            out, _ = await asyncio.wait_for(proc.communicate(), timeout)
        except BaseException:
            with contextlib.suppress(ProcessLookupError):
                proc.kill()
            await proc.wait()
            raise
        return proc.returncode or 0, out.decode(errors="replace")

    def socket(
        self, host: str, family: int = socket.AF_INET, kind: int = socket.SOCK_STREAM
    ) -> socket.socket:
        """A socket of this process's that lives in ``host`` (see :func:`socket_in`)."""
        return socket_in(self.hosts[host].ns, family, kind)

    # -- faults --------------------------------------------------------------------------------

    def link(self, host: str, up: bool) -> None:
        """Plug ``host``'s cable in (``up``) or pull it (its bridge end set down). Plugged in,
        it returns once both ends carry (up to 5 s): a veth's far end comes up a moment later.
        Every host's neighbour cache is flushed then, as a replugged cable would leave it: an
        address that went unanswered while cut off is otherwise "no route to host" for seconds."""
        h = self.hosts[host]
        _ip("link", "set", h.link, "up" if up else "down")
        if up:
            for other in self.hosts.values():
                _ip("-n", other.ns, "neigh", "flush", "all", check=False)
        deadline = time.monotonic() + 5.0
        while up and time.monotonic() < deadline:
            ends = _ip("-o", "link", "show", h.link, check=False)
            ends += _ip("-n", h.ns, "-o", "link", "show", "eth0", check=False)
            if ends.count("state UP") == 2:
                return
            time.sleep(0.02)

    @contextlib.asynccontextmanager
    async def partition(self, host: str, seconds: float | None = None) -> AsyncIterator[None]:
        """``host`` cut off while inside (for ``seconds`` first, if given); plugged in again
        on the way out, whatever happens."""
        self.link(host, False)
        try:
            if seconds is not None:
                await asyncio.sleep(seconds)
            yield
        finally:
            if not self.closed:
                self.link(host, True)


def _close_all() -> None:
    for lab in list(_labs):
        with contextlib.suppress(Exception):
            lab.close()


atexit.register(_close_all)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m mover._netlab --sweep [--all]``: remove the leftovers of dead labs (with
    ``--all``, of every lab: when no test is running); prints what it removed."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m mover._netlab", description=main.__doc__)
    parser.add_argument("--sweep", action="store_true", help="remove dead labs' leftovers")
    parser.add_argument("--all", action="store_true", help="with --sweep: every lab's")
    args = parser.parse_args(argv)
    if not args.sweep:
        parser.print_usage()
        return 2
    if reason := unavailable():
        print(f"python -m mover._netlab: {reason}")
        return 1
    for name in sweep(all_tags=args.all):
        print(f"removed {name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
