"""The Must-show of the viewer: a lock-step world with robots running a program (real
processes over zenoh), ``mover view`` as a process, its page loaded in headless Chromium, and
the world's data on the canvas: the robots' own colours in the screenshot, which is kept under
the test's temporary folder. Then the run's recording, played by ``mover replay``, the same way.

Skipped, with the reason, when no Chromium can be had (``.ci/run`` installs Debian's).
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
from pathlib import Path

import pytest

pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")

from mover import launch
from mover._config import free_port
from mover.testing import cluster
from sim_hw.continuous._record import track_colours
from sim_hw.view._entities import rgb

from ._browser import (
    ENOUGH,
    all_shown,
    browser_or_skip,
    distinct_pixels,
    replay_in_browser,
    screenshots,
    shown,
)
from .test_view_cli import expect_line

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[3]
WORLD = str(ROOT / "worlds" / "search_and_rescue.toml")
NAMES = ["ernst", "moseley"]
_ALL = track_colours(["elvis", "ernst", "moseley"])  # the world file's robots, sorted
COLOURS = {n: rgb(_ALL[n]) for n in NAMES}


@pytest.mark.slow
@pytest.mark.timeout(300)
async def test_the_world_reaches_the_browser_live_and_replayed(tmp_path: Path) -> None:
    browser = browser_or_skip()
    rec = tmp_path / "run.jsonl"
    async with cluster(cwd=ROOT) as c, c.launcher() as node:
        await c.world(WORLD, "--record", str(rec), "--state-rate", "5", expect=len(NAMES))
        await c.robots(*NAMES)
        run = asyncio.ensure_future(launch(node, "search_and_rescue", NAMES, {}, run="seen"))
        try:
            port = free_port()
            view = await c.start(
                "mover._cli", "view", "--port", str(port), "--links", "3", ready=None
            )
            url = (await expect_line(view, "mover view: open", 60)).split()[-1]
            await expect_line(view, "showing world 'world'")
            live = await asyncio.to_thread(
                screenshots,
                browser,
                url,
                tmp_path / "live.png",
                all_shown(COLOURS),
                profile=tmp_path / "chromium-live",
            )
            assert not run.done() or "result" in str(run.result()), "the program ran"
        finally:
            run.cancel()
            with contextlib.suppress(BaseException):
                await run
        counts = shown(live, COLOURS)
        assert distinct_pixels(live) > 20_000, "the page is not blank"
        assert all(v >= ENOUGH for v in counts.values()), (counts, tmp_path / "live.png")
        view.send_signal(signal.SIGINT)
        assert await asyncio.wait_for(view.wait(), 30) == 0
    async with cluster(cwd=ROOT) as c:
        replay, played = await replay_in_browser(
            c, browser, rec, tmp_path / "replay.png", all_shown(COLOURS)
        )
        counts = shown(played, COLOURS)
        assert all(v >= ENOUGH for v in counts.values()), (counts, tmp_path / "replay.png")
        replay.send_signal(signal.SIGINT)
        assert await asyncio.wait_for(replay.wait(), 30) == 0
