"""The demo's recording exported as MCAP (``mover replay world.jsonl --out run.mcap``) and
played by ``mover replay run.mcap`` in rerun's web viewer, loaded in headless Chromium: the
three robots' own colours on the canvas (the screenshot is kept under the test's temporary
folder). Skipped, with the reason, when no Chromium can be had (``.ci/run`` installs Debian's).
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")
pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")

from experiments.demo_runs import run_demo
from mover._cli import main
from mover._config import free_port
from mover.testing import cluster
from sim_hw.continuous._record import track_colours
from sim_hw.view._entities import rgb

from ._browser import count_near, distinct_pixels, find_browser, screenshots
from .test_view_cli import expect_line

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[3]
NAMES = ["elvis", "ernst", "moseley"]  # the demo's robots
COLOURS = track_colours(NAMES)
ENOUGH = 100  # pixels of a robot's colour: a disc of ~12 px radius has ~450


def _robots_on_page(image: object) -> bool:
    return all(count_near(image, rgb(COLOURS[n])) >= ENOUGH for n in NAMES)


@pytest.mark.slow
@pytest.mark.timeout(300)
async def test_the_demos_mcap_replays_in_the_browser(tmp_path: Path) -> None:
    browser = find_browser()
    if browser is None:
        pytest.skip("no Chromium on PATH (Debian: apt-get install chromium)")
    code, out = await run_demo(tmp_path / "demo")
    assert code == 0, out
    mcap = tmp_path / "run.mcap"
    assert main(["replay", str(tmp_path / "demo" / "world.jsonl"), "--out", str(mcap)]) == 0
    async with cluster(cwd=ROOT) as c:
        port = free_port()
        replay = await c.start("mover._cli", "replay", str(mcap), "--port", str(port), ready=None)
        url = (await expect_line(replay, "mover replay: open", 60)).split()[-1]
        played = await asyncio.to_thread(
            screenshots,
            browser,
            url,
            tmp_path / "replay.png",
            _robots_on_page,
            profile=tmp_path / "chromium",
        )
        counts = {n: count_near(played, rgb(COLOURS[n])) for n in NAMES}
        assert distinct_pixels(played) > 20_000, "the page is not blank"
        assert all(v >= ENOUGH for v in counts.values()), (counts, tmp_path / "replay.png")
    # The replay is ended by the cluster. Ctrl-C is test_view_ctrl_c's: here, once, after the
    # browser had loaded the demo's replay, SIGINT did not end it within 30 s (without a
    # browser it ends in 0.2 s, from the .jsonl and the .mcap alike).
