"""The rerun server a view is shown by: a gRPC proxy and rerun's own web viewer, on loopback.

The server is the ``rerun`` program of the ``rerun-sdk`` package (``rerun --serve-web``), run
as a child process: it serves the web viewer's page, script and Wasm from the package itself
(no network needed), and buffers what the view logs for every browser that connects, late ones
included, up to :data:`MEMORY_LIMIT` (then the oldest data goes). The SDK's in-process
``serve_grpc`` would do the same but listens on every interface with no way to say otherwise;
a world's positions are the team's business, so the child binds ``--bind`` (loopback by
default). The child dies with its parent (``PR_SET_PDEATHSIG``), a SIGKILLed view included. It
runs in a session of its own: a terminal's Ctrl-C reaches the view alone, which closes its
recording (rerun's client would print an error for a server already gone) and then stops the
child.

Costs (measured on the project's 2-core machine, rough): the server child idles at ~0 CPU and
stays under 0.01 CPU-s/s while a world runs; rerun-sdk 0.41 is a 170 MB wheel (with pyarrow,
its one large dependency, 226 MB to download) and 521 MB installed (with pyarrow 697 MB).
"""

from __future__ import annotations

import importlib.util
import logging
import os
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path
from typing import IO
from urllib.parse import quote

from mover.cli import UsageError, guarded

log = logging.getLogger("sim_hw.view")

MEMORY_LIMIT = "512MiB"
"""What the server keeps for late browsers at most (rerun drops the oldest data past it)."""

START_TIMEOUT = 20.0
"""Seconds the server has to start listening."""


def rerun_binary() -> Path:
    """The ``rerun`` program shipped in the ``rerun-sdk`` wheel (UsageError when missing)."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is None or spec.origin is None or importlib.util.find_spec("rerun") is None:
        raise UsageError("the viewer needs rerun-sdk: pip install 'mover[view]'")
    exe = Path(spec.origin).parent / "rerun"
    if not exe.is_file():
        raise UsageError(f"rerun-sdk is installed without its viewer program ({exe})")
    return exe


def _free(bind: str, port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the server will
        try:
            s.bind((bind, port))
        except OSError:
            return False
    return True


def _any_port(bind: str) -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((bind, 0))
        return int(s.getsockname()[1])


def _listening(bind: str, port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(0.5)
        return s.connect_ex((bind, port)) == 0


class ViewerServer:
    """``rerun --serve-web`` on ``bind``: the page on ``port``, the gRPC proxy on a free port.

    Use as a context manager: on entry the server listens (or a one-line UsageError says why
    not: the port is taken, rerun is missing, it did not start); on exit it is stopped.
    """

    def __init__(self, port: int = 9090, *, bind: str = "127.0.0.1") -> None:
        self.port, self.bind = port, bind
        self.grpc_port = 0
        self._proc: subprocess.Popen[bytes] | None = None
        self._err: IO[bytes] | None = None

    @property
    def grpc_url(self) -> str:
        """Where the SDK sends what it logs."""
        return f"rerun+http://{self.bind}:{self.grpc_port}/proxy"

    @property
    def url(self) -> str:
        """The page to open in a browser."""
        host = "127.0.0.1" if self.bind in ("0.0.0.0", "::") else self.bind
        proxy = f"rerun+http://{host}:{self.grpc_port}/proxy"
        return f"http://{host}:{self.port}/?url={quote(proxy, safe=':/')}"

    def __enter__(self) -> ViewerServer:
        exe = rerun_binary()
        if not _free(self.bind, self.port):
            raise UsageError(
                f"port {self.port} on {self.bind} is taken (another mover view?): "
                "choose another with --port"
            )
        self.grpc_port = _any_port(self.bind)
        self._err = tempfile.TemporaryFile()
        args = [
            str(exe), "--serve-web", "--bind", self.bind, "--port", str(self.grpc_port),
            "--web-viewer-port", str(self.port), "--server-memory-limit", MEMORY_LIMIT,
        ]  # fmt: skip
        env = {**os.environ, "RUST_LOG": "warn"}
        self._proc = subprocess.Popen(
            guarded(args, signal.SIGTERM),  # it dies with the view, a SIGKILLed one too
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=self._err,
            env=env,
            start_new_session=True,  # a terminal's Ctrl-C is the view's to handle, not rerun's
        )
        deadline = time.monotonic() + START_TIMEOUT
        while not (_listening(self.bind, self.port) and _listening(self.bind, self.grpc_port)):
            if self._proc.poll() is not None or time.monotonic() > deadline:
                why = self._last_error() or "it did not start"
                self.__exit__()
                raise UsageError(f"the rerun server on port {self.port} failed: {why}")
            time.sleep(0.05)
        log.info(
            "rerun server pid %d: page on %d, gRPC on %d", self._proc.pid, self.port, self.grpc_port
        )
        return self

    def alive(self) -> bool:
        """Whether the server still runs."""
        return self._proc is not None and self._proc.poll() is None

    def _last_error(self) -> str:
        if self._err is None:
            return ""
        self._err.seek(0)
        lines = [ln.strip() for ln in self._err.read().decode(errors="replace").splitlines()]
        lines = [ln for ln in lines if ln]
        return lines[-1][-300:] if lines else ""

    def __exit__(self, *exc: object) -> None:
        proc, self._proc = self._proc, None
        if proc is not None and proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)
        if self._err is not None:
            self._err.close()
            self._err = None
