"""Starting real robot processes for integration tests (real zenoh on 127.0.0.1)."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from collections.abc import AsyncIterator, Sequence
from contextlib import asynccontextmanager
from dataclasses import dataclass, field
from pathlib import Path

from mover import NodeConfig, Team, free_port

ROOT = Path(__file__).resolve().parents[2]


@dataclass
class Cluster:
    """A seed endpoint that every process connects to, and the processes started."""

    team: Team
    port: int = field(default_factory=free_port)
    procs: list[asyncio.subprocess.Process] = field(default_factory=list)

    @property
    def seed(self) -> NodeConfig:
        """Settings for the node that listens on the seed port (the test's own node)."""
        return NodeConfig(listen=(f"tcp/127.0.0.1:{self.port}",))

    @property
    def peer(self) -> NodeConfig:
        """Settings for every other node: a free port of its own, connecting to the seed."""
        return NodeConfig(connect=(f"tcp/127.0.0.1:{self.port}",))

    async def start(
        self,
        module: str,
        *args: str,
        team: Team | None = None,
        ready: str | None = "READY",
        timeout: float = 20.0,
        config: NodeConfig | None = None,
    ) -> asyncio.subprocess.Process:
        """Start ``python -m module args`` and wait until it prints ``ready`` (None: no wait)."""
        env = dict(os.environ)
        env.update((team or self.team).env())
        env.update((config or self.peer).env())
        env["PYTHONPATH"] = str(ROOT)
        proc = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            module,
            *args,
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
            env=env,
            cwd=ROOT,
        )
        self.procs.append(proc)
        if ready is None:
            return proc
        assert proc.stdout is not None
        async with asyncio.timeout(timeout):
            while True:
                line = (await proc.stdout.readline()).decode()
                if not line:
                    raise RuntimeError(f"{module} {args} exited before it was ready")
                if line.startswith(ready):
                    return proc

    async def robot(
        self, name: str, *extra: str, team: Team | None = None
    ) -> asyncio.subprocess.Process:
        """Start a test robot (tests/helpers/robot_proc.py)."""
        return await self.start("tests.helpers.robot_proc", "--name", name, *extra, team=team)

    async def stop(self) -> None:
        for proc in self.procs:
            if proc.returncode is None:
                try:
                    proc.send_signal(signal.SIGCONT)
                    proc.kill()
                except ProcessLookupError:
                    pass
        for proc in self.procs:
            try:
                async with asyncio.timeout(10):
                    await proc.wait()
            except TimeoutError:
                pass


@asynccontextmanager
async def cluster(team: Team | None = None) -> AsyncIterator[Cluster]:
    """A cluster whose processes are all killed on exit."""
    c = Cluster(team or Team.generate("alpha"))
    try:
        yield c
    finally:
        await c.stop()


async def robots(c: Cluster, specs: Sequence[tuple[str, Sequence[str]]]) -> None:
    """Start several test robots at once."""
    await asyncio.gather(*(c.robot(name, *extra) for name, extra in specs))
