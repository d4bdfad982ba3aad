"""The demo's recording exported as MCAP (``mover replay world.jsonl --out run.mcap``) and
played by ``mover replay run.mcap`` in rerun's web viewer, loaded in headless Chromium: the
three robots' own colours on the canvas (the screenshot is kept under the test's temporary
folder). Skipped, with the reason, when no Chromium can be had (``.ci/run`` installs Debian's).
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")
pytest.importorskip("mcap_ros2", reason="needs the mcap extra: pip install 'mover[mcap]'")

from experiments.demo_runs import run_demo
from mover._cli import main
from mover.testing import cluster
from sim_hw.continuous._record import track_colours
from sim_hw.view._entities import rgb

from ._browser import ENOUGH, all_shown, browser_or_skip, distinct_pixels, replay_in_browser, shown

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[3]
NAMES = ["elvis", "ernst", "moseley"]  # the demo's robots
COLOURS = {n: rgb(c) for n, c in track_colours(NAMES).items()}


@pytest.mark.slow
@pytest.mark.timeout(300)
async def test_the_demos_mcap_replays_in_the_browser(tmp_path: Path) -> None:
    browser = browser_or_skip()
    code, out = await run_demo(tmp_path / "demo")
    assert code == 0, out
    mcap = tmp_path / "run.mcap"
    assert main(["replay", str(tmp_path / "demo" / "world.jsonl"), "--out", str(mcap)]) == 0
    async with cluster(cwd=ROOT) as c:
        _, played = await replay_in_browser(
            c, browser, mcap, tmp_path / "replay.png", all_shown(COLOURS)
        )
        counts = shown(played, COLOURS)
        assert distinct_pixels(played) > 20_000, "the page is not blank"
        assert all(v >= ENOUGH for v in counts.values()), (counts, tmp_path / "replay.png")
    # The replay is ended by the cluster. Ctrl-C is test_view_ctrl_c's: here, once, after the
    # browser had loaded the demo's replay, SIGINT did not end it within 30 s (without a
    # browser it ends in 0.2 s, from the .jsonl and the .mcap alike).
