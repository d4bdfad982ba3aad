"""``mover view`` as a process over real zenoh (no browser): it waits for a world, shows it,
says when it is gone and shows it again when it is back; a taken port and a bad flag are one
line; Ctrl-C is one line and a clean exit, and takes rerun's server with it."""

from __future__ import annotations

import asyncio
import signal
import socket
from pathlib import Path

import pytest

pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")

from mover._cli import main
from mover._config import free_port
from mover.testing import cluster, first_line

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[3]
WORLD = str(ROOT / "worlds" / "search_and_rescue.toml")


async def expect_line(proc: asyncio.subprocess.Process, text: str, timeout: float = 30.0) -> str:
    """The next line of ``proc``'s output that contains ``text`` (its earlier lines skipped)."""
    line = await first_line(proc, lambda line: text in line, timeout)
    if line is None:
        raise AssertionError(f"the process ended before saying {text!r}")
    return line.strip()


def _listening(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) == 0


async def test_view_waits_shows_loses_and_shows_again_a_world(tmp_path: Path) -> None:
    port = free_port()
    async with cluster(cwd=ROOT) as c, c.launcher():
        view = await c.start("mover._cli", "view", "--port", str(port), ready="mover view: open")
        await expect_line(view, "waiting for a world")
        assert _listening(port)
        log = tmp_path / "again.log"
        again = await c.start("mover._cli", "view", "--port", str(port), ready=None, log=log)
        assert await asyncio.wait_for(again.wait(), 60) == 2
        assert log.read_text().strip().splitlines() == [
            f"mover view: port {port} on 127.0.0.1 is taken (another mover view?): "
            "choose another with --port"
        ]
        world = await c.world(WORLD, expect=1)
        line = await expect_line(view, "showing world")
        assert line == "mover view: showing world 'world' (search-and-rescue, continuous)"
        world.kill()
        await world.wait()
        line = await expect_line(view, "is gone")
        assert line == "mover view: world 'world' is gone; waiting for it to come back"
        await c.world(WORLD, expect=1)
        await expect_line(view, "showing world 'world'")
        view.send_signal(signal.SIGINT)
        assert view.stdout is not None
        rest = (await asyncio.wait_for(view.stdout.read(), 30)).decode().splitlines()
        assert await asyncio.wait_for(view.wait(), 30) == 0
        assert rest == ["mover view: stopped"]
    for _ in range(50):  # rerun's server went with it
        if not _listening(port):
            break
        await asyncio.sleep(0.1)
    assert not _listening(port)


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--port", "0"], "--port: must be from 1 to 65535, got 0"),
        (["--links", "-1"], "must be a finite number above 0"),
        (["--record", "x.txt"], "--record must name a .rrd file"),
        (["--world", "a b"], "bad member name"),
    ],
)
def test_bad_flags_are_one_line(
    args: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    try:
        code = main(["view", *args])
    except SystemExit as exc:  # argparse's own errors
        code = int(exc.code or 0)
    assert code == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len([ln for ln in err if says in ln]) == 1, err


async def test_view_draws_a_grid_world_from_its_frames(tmp_path: Path) -> None:
    from rerun.chunk import RrdReader

    grid = tmp_path / "g.txt"
    grid.write_text("#######\n#B...R#\n#.#...#\n#######\n")
    rrd = tmp_path / "grid.rrd"
    async with cluster(cwd=ROOT) as c, c.launcher():
        await c.start("mover._cli", "gridworld", str(grid), ready="READY")
        view = await c.start(
            "mover._cli", "view", "--port", str(free_port()), "--record", str(rrd), ready=None
        )
        line = await expect_line(view, "showing world")
        assert line == f"mover view: showing world 'gridworld' (grid, grid), recording to {rrd}"
        await asyncio.sleep(1.0)  # a few frames asked for
        view.send_signal(signal.SIGINT)
        assert await asyncio.wait_for(view.wait(), 30) == 0
    paths = {chunk.entity_path for chunk in RrdReader(rrd).stream().to_chunks()}
    assert {"/arena", "/grid/cells", "/robots"} <= paths


async def test_a_killed_view_leaves_no_server_behind() -> None:
    port = free_port()
    async with cluster(cwd=ROOT) as c, c.launcher():
        view = await c.start("mover._cli", "view", "--port", str(port), ready="mover view: open")
        assert _listening(port)
        view.kill()  # SIGKILL: no clean-up of its own runs
        await view.wait()
        for _ in range(50):  # the server gets SIGTERM as its parent dies
            if not _listening(port):
                break
            await asyncio.sleep(0.1)
        assert not _listening(port)
