"""The PNG of ``mover replay FILE --out PNG`` and recordings cut short (a SIGKILLed world)."""

from __future__ import annotations

import asyncio
import json
import logging
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.colors import to_hex
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon

from mover._cli import main
from sim_hw import Recorder, World, WorldServer, in_process, load_world, read_recording
from sim_hw.continuous._record import draw_recording, run_end, track_colours
from sim_hw.continuous._walker import random_walk

WORLDS = Path(__file__).parents[3] / "worlds"


async def _search_and_rescue(path: Path, ticks: int = 60) -> None:
    """A short in-process run on the search-and-rescue world, recorded."""
    world = World(load_world(WORLDS / "search_and_rescue.toml"), seed=3)
    recorder = Recorder(path, world)
    server = WorldServer(world, expect=2)
    server.door.on_tick.append(recorder)

    async def robot(rid: str, seed: int) -> None:
        hw = await in_process(server, rid)
        await random_walk(hw, np.random.default_rng(seed), ticks)

    await asyncio.gather(robot("ernst", 1), robot("moseley", 2))
    await server.door.aclose()
    recorder.close()


async def test_the_png_of_the_search_and_rescue_recording(tmp_path: Path) -> None:
    rec = tmp_path / "run.jsonl"
    await _search_and_rescue(rec)
    header, ticks = read_recording(rec)
    assert header["radii"]["ernst"] == pytest.approx(0.15)
    fig = draw_recording(header, ticks)
    ax = fig.axes[0]
    circles = [p for p in ax.patches if isinstance(p, Circle)]
    rock = next(i for i in header["immovables"] if i["id"] == "rock")
    assert rock["shape"] == "circle"
    assert any(
        tuple(c.center) == tuple(rock["center"]) and c.radius == rock["radius"] for c in circles
    ), "the round immovable is drawn as a circle"
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    colours = track_colours(["elvis", "ernst", "moseley"])  # the world file's robots
    for robot in ("ernst", "moseley"):
        line = lines[robot]
        assert to_hex(line.get_color()) == colours[robot]
        xs, ys = line.get_data()
        ends = [ln for ln in ax.get_lines() if ln.get_label() == "_end"]
        end = next(e for e in ends if e.get_xydata().tolist() == [[xs[-1], ys[-1]]])
        assert to_hex(end.get_color()) == colours[robot], "the end marker in the line's colour"
        starts = [ln for ln in ax.get_lines() if ln.get_label() == "_start"]
        start = next(s for s in starts if s.get_xydata().tolist() == [[xs[0], ys[0]]])
        assert to_hex(start.get_markeredgecolor()) == colours[robot]
    outlines = [p for p in ax.patches if isinstance(p, Polygon) and not p.get_fill()]
    assert len(outlines) == 2, "the box outlined where it started and where it ended"
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    assert f"run ended at {run_end(ticks):.1f} s" in ax.get_title()
    legend = ax.get_legend()
    shown = {
        t.get_text(): h for t, h in zip(legend.get_texts(), legend.legend_handles, strict=True)
    }
    for robot in ("ernst", "moseley"):
        assert isinstance(shown[robot], Line2D)
        assert to_hex(shown[robot].get_color()) == colours[robot], "the legend's colours match"
    assert {"start", "end"} <= shown.keys()
    # obstacles solid, immovables hatched: told apart on the page and in the legend
    obstacle, immovable = shown["obstacle"], shown["immovable object"]
    assert not obstacle.get_hatch() and immovable.get_hatch()
    rock_patch = next(c for c in circles if tuple(c.center) == tuple(rock["center"]))
    assert rock_patch.get_hatch() == immovable.get_hatch()
    png = tmp_path / "run.png"
    assert main(["replay", str(rec), "--out", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _lines(ticks: list[dict[str, Any]]) -> list[str]:
    header = {"type": "header", "name": "t", "size": [4.0, 3.0], "seed": 0, "obstacles": [],
              "boxes": [], "immovables": [], "markers": []}  # fmt: skip
    return [json.dumps(header)] + [json.dumps({"type": "tick", **t}) for t in ticks]


def _tick(n: int, x: float) -> dict[str, Any]:
    return {"tick": n, "t": n / 10, "robots": {"r": [x, 1.0, 0.0, ""]}, "boxes": {}}


def test_the_run_ends_when_nothing_moves_any_more() -> None:
    ticks = [_tick(0, 1.0), _tick(1, 1.5), _tick(2, 2.0), _tick(3, 2.0), _tick(4, 2.0)]
    assert run_end(ticks) == pytest.approx(0.2)
    assert run_end([_tick(0, 1.0), _tick(1, 1.0)]) == pytest.approx(0.1)  # nothing moved
    assert run_end([]) == 0.0


def test_a_recording_cut_short_replays_to_its_last_whole_line(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = _lines([_tick(n, 1.0 + n / 10) for n in range(5)])
    cut = tmp_path / "cut.jsonl"
    cut.write_text("\n".join(lines) + "\n" + lines[-1][: len(lines[-1]) // 2])  # SIGKILLed
    with caplog.at_level(logging.WARNING, logger="sim_hw.record"):
        _, ticks = read_recording(cut)
    assert [t["tick"] for t in ticks] == [0, 1, 2, 3, 4]
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert "line 7 is cut short" in warnings[0].getMessage()
    assert "replaying up to tick 4" in warnings[0].getMessage()
    caplog.clear()
    png = tmp_path / "cut.png"
    assert main(["replay", str(cut), "--out", str(png)]) == 0
    assert png.is_file()
    assert capsys.readouterr().out.strip() == str(png)


def test_a_bad_line_inside_a_recording_is_still_an_error(tmp_path: Path) -> None:
    lines = _lines([_tick(n, 1.0) for n in range(3)])
    bad = tmp_path / "bad.jsonl"
    bad.write_text("\n".join([*lines[:2], lines[2][:10], *lines[3:]]) + "\n")
    with pytest.raises(ValueError, match="line 3: not JSON"):
        read_recording(bad)


def test_replay_refuses_other_outputs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rec = tmp_path / "r.jsonl"
    rec.write_text("\n".join(_lines([_tick(0, 1.0)])) + "\n")
    assert main(["replay", str(rec), "--out", str(tmp_path / "x.jpg")]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("mover replay")]
    assert err == [
        f"mover replay: --out must name a .png, .rrd or .mcap file, got '{tmp_path}/x.jpg'"
    ]
