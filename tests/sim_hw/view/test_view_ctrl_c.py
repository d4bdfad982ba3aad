"""Ctrl-C on ``mover view`` in a terminal: the signal goes to the whole foreground process
group. The view says one line and exits 0; rerun's server, in a session of its own, is not
interrupted under the view's open recording (its client printed an error for a server gone)."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from pathlib import Path

import pytest

pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")

from mover._config import free_port
from mover.testing import cluster
from tests.helpers.procs import shell_env

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[3]
WORLD = str(ROOT / "worlds" / "search_and_rescue.toml")


async def test_ctrl_c_to_the_views_process_group_is_one_line_and_a_clean_exit() -> None:
    async with cluster(cwd=ROOT) as c, c.launcher():
        await c.world(WORLD, expect=1)
        view = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "mover", "view", "--port", str(free_port()), env=shell_env(c),
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
            start_new_session=True,  # its own process group, as a terminal's foreground job
        )  # fmt: skip
        assert view.stdout is not None and view.stderr is not None
        try:
            async with asyncio.timeout(60):
                while b"showing world" not in await view.stdout.readline():
                    pass
            await asyncio.sleep(1.0)  # the view sends its frames meanwhile
            os.killpg(view.pid, signal.SIGINT)  # Ctrl-C: the group, rerun's server included
            out, err = await asyncio.wait_for(view.communicate(), 30)
        finally:
            if view.returncode is None:
                os.killpg(view.pid, signal.SIGKILL)
                await view.wait()
    assert view.returncode == 0
    assert out.decode().splitlines() == ["mover view: stopped"]
    assert err.decode().strip() == ""
