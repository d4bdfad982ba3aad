"""Starting real robot processes for integration tests (real zenoh on 127.0.0.1).

The machinery is the public ``mover.testing``; this adds the test robot of tests/helpers.
"""

from __future__ import annotations

import asyncio
import os
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from mover import Node, TeamCredentials
from mover.testing import Cluster as _Cluster

ROOT = Path(__file__).resolve().parents[2]


class Cluster(_Cluster):
    """A cluster that can also start the test robot (tests/helpers/robot_proc.py)."""

    async def robot(
        self, name: str, *extra: str, team: TeamCredentials | None = None
    ) -> asyncio.subprocess.Process:
        """Start a test robot."""
        return await self.start("tests.helpers.robot_proc", "--name", name, *extra, team=team)

    async def joined(self, name: str, node: Node) -> asyncio.subprocess.Process:
        """Start the test robot ``name`` and wait (10 s at most) until ``node`` sees it."""
        proc = await self.robot(name)
        await node.membership.wait_for({name}, timeout=10)
        return proc


@asynccontextmanager
async def cluster(team: TeamCredentials | None = None) -> AsyncIterator[Cluster]:
    """A cluster rooted at the repository, whose processes are all killed on exit."""
    c = Cluster(team or TeamCredentials.generate("alpha"), cwd=ROOT, env={"PYTHONPATH": str(ROOT)})
    try:
        yield c
    finally:
        await c.stop()


def shell_env(cluster: _Cluster) -> dict[str, str]:
    """The environment of a user's shell that runs ``mover`` verbs on ``cluster``'s team: this
    one's, with the team's name and key and the seed endpoint (a key file it names is dropped,
    so that the key given here is the one read)."""
    env = {**os.environ, **cluster.team.env(), "MOVER_CONNECT": f"tcp/127.0.0.1:{cluster.port}"}
    env.pop("MOVER_TEAM_KEY_FILE", None)
    return env


async def terminate(proc: asyncio.subprocess.Process, grace: float) -> None:
    """End ``proc`` (if it still runs): SIGTERM, at most ``grace`` s for it to exit, then
    SIGKILL; return once it has ended (a test leaves no process behind)."""
    if proc.returncode is not None:
        return
    proc.terminate()
    try:
        await asyncio.wait_for(proc.wait(), grace)
    except TimeoutError:
        proc.kill()
        await proc.wait()
