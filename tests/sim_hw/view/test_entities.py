"""The scene conversion (a world's scene and state frames → rerun entities), without a viewer:
the entities themselves, and a replay saved to a ``.rrd`` file read back with rerun's reader."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rr = pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")

from mover._cli import main  # noqa: E402
from sim_hw.continuous._record import PALETTE  # noqa: E402
from sim_hw.view import _entities  # noqa: E402
from sim_hw.view._entities import Drawing, led_colour, rgb  # noqa: E402

HEADER: dict[str, Any] = {
    "type": "header",
    "kind": "continuous",
    "name": "unit",
    "size": [4.0, 3.0],
    "obstacles": [
        {"shape": "circle", "center": [1.0, 1.0], "radius": 0.3},
        {"shape": "box", "center": [3.0, 2.0], "size": [0.4, 0.2], "angle": 0.0},
    ],
    "boxes": [{"id": "crate", "center": [2.0, 1.5], "size": [0.6, 0.4], "angle": 0.0}],
    "immovables": [
        {"id": "rock", "shape": "circle", "center": [0.5, 2.5], "radius": 0.2},
        {"id": "pillar", "shape": "box", "center": [3.5, 0.5], "size": [0.2, 0.2], "angle": 0.0},
    ],
    "markers": [{"kind": "target", "id": "goal", "center": [3.5, 2.5], "radius": 0.2}],
    "radii": {"*": 0.15, "ann": 0.2},
}


def _frame(tick: int, ann: tuple[float, float, float], led: str = "") -> dict[str, Any]:
    return {
        "tick": tick,
        "t": tick * 0.1,
        "robots": {"ann": [*ann, led], "bob": [3.0, 1.0, math.pi / 2, ""]},
        "boxes": {"crate": [2.0, 1.5, 0.0]},
        "marked": {},
    }


def _by_path(entities: list[tuple[str, Any, bool]]) -> dict[str, tuple[Any, bool]]:
    return {path: (arch, static) for path, arch, static in entities}


def _positions(arch: Any) -> list[list[float]]:
    positions: list[list[float]] = np.asarray(arch.positions.pa_array.to_pylist()).tolist()
    return positions


def _strips(arch: Any) -> list[list[list[float]]]:
    return [np.asarray(s).tolist() for s in arch.strips.pa_array.to_pylist()]


def test_the_static_scene_draws_circles_as_circles_and_boxes_as_outlines() -> None:
    scene = _by_path(Drawing(HEADER).scene())
    assert all(static for _, static in scene.values())
    discs, _ = scene["obstacles/circles"]
    assert _positions(discs) == [[1.0, 2.0]]  # y is flipped: 3 - 1
    assert discs.radii.pa_array.to_pylist() == [pytest.approx(0.3)]
    (outline,) = _strips(scene["obstacles/outlines"][0])
    assert len(outline) == 5 and outline[0] == outline[-1]  # a closed box outline
    assert {round(x, 3) for x, _ in outline} == {2.8, 3.2}
    assert _positions(scene["immovables/circles"][0]) == [[0.5, 0.5]]
    assert scene["immovables/outlines"][0].labels.pa_array.to_pylist() == ["pillar"]
    assert scene["targets"][0].labels.pa_array.to_pylist() == ["goal"]
    arena = _strips(scene["arena"][0])[0]
    assert arena[:3] == [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]]


def test_the_ceiling_draws_eye_bots_views_their_theta0_and_the_areas() -> None:
    assert not any(p.startswith(("eyebots", "areas")) for p in _by_path(Drawing(HEADER).scene()))
    header = {
        **HEADER,
        "eyebots": [{"id": "e1", "center": [1.0, 1.0], "heading": math.pi / 2, "view": 0.5}],
        "areas": [{"id": "source", "center": [0.5, 0.5], "radius": 0.4}],
    }
    scene = _by_path(Drawing(header).scene())
    (view,) = _strips(scene["eyebots/view"][0])
    assert {round(math.dist(p, (1.0, 2.0)), 6) for p in view} == {0.5}  # its disc, y flipped
    (theta0,) = _strips(scene["eyebots/theta0"][0])
    assert theta0[0] == [1.0, 2.0] and theta0[1] == [pytest.approx(1.0), pytest.approx(1.7)]
    assert scene["eyebots/theta0"][0].labels.pa_array.to_pylist() == ["e1"]
    assert scene["areas"][0].labels.pa_array.to_pylist() == ["source"]


def test_a_frame_draws_robots_with_heading_led_name_and_boxes() -> None:
    drawing = Drawing(HEADER)
    frame = _by_path(drawing.frame(_frame(5, (1.0, 1.0, 0.0), led="red")))
    robots, static = frame["robots"]
    assert not static
    assert _positions(robots) == [[1.0, 2.0], [3.0, 2.0]]
    assert robots.labels.pa_array.to_pylist() == ["ann", "bob"]
    assert robots.radii.pa_array.to_pylist() == pytest.approx([0.2, 0.15])
    colours = robots.colors.pa_array.to_pylist()
    assert colours[0] == int.from_bytes(bytes([*rgb(PALETTE[0]), 255]), "big")  # ann, sorted first
    heads = _strips(frame["robots/heading"][0])
    assert heads[0] == [[1.0, 2.0], [pytest.approx(1.2), pytest.approx(2.0)]]  # facing +x
    assert heads[1][1] == [pytest.approx(3.0), pytest.approx(2.0 - 0.15)]  # facing +y: up
    led = frame["robots/led"][0]
    assert _positions(led) == [[1.0, 2.0]]  # only ann's LED is on
    assert led.colors.pa_array.to_pylist() == [0xFF0000FF]
    (crate,) = _strips(frame["boxes"][0])
    assert {round(x, 3) for x, _ in crate} == {1.7, 2.3}
    assert "links" not in frame


def test_led_colours() -> None:
    assert led_colour("") is None
    assert led_colour("green") == (0, 128, 0)
    assert led_colour("#0000ff") == (0, 0, 255)
    assert led_colour("mark:goal") == (255, 255, 255)  # a message, not a colour


def test_trails_grow_in_pieces_and_old_pieces_are_cleared(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_entities, "TRAIL_PIECE", 4)
    monkeypatch.setattr(_entities, "TRAIL_PIECES", 2)
    drawing = Drawing(HEADER)
    paths: list[str] = []
    cleared: list[str] = []
    for n in range(12):
        for path, arch, _ in drawing.frame(_frame(n, (0.5 + 0.1 * n, 1.0, 0.0))):
            if path.startswith("trails/ann/"):
                (cleared if isinstance(arch, rr.Clear) else paths).append(path)
    assert paths[0] == "trails/ann/0"
    assert len(set(paths)) == 4  # 12 points in pieces of 4 sharing their ends
    assert cleared == ["trails/ann/0", "trails/ann/1"]  # two kept at most
    assert not any(p.startswith("trails/bob/") for p in paths)  # bob did not move


def test_links_join_robots_within_range() -> None:
    near = _by_path(Drawing(HEADER, links=2.5).frame(_frame(1, (1.0, 1.0, 0.0))))
    assert len(_strips(near["links"][0])) == 1
    far = _by_path(Drawing(HEADER, links=1.0).frame(_frame(1, (1.0, 1.0, 0.0))))
    assert _strips(far["links"][0]) == []


def test_a_grid_frame_draws_cells_marks_and_robots() -> None:
    header = {"type": "header", "kind": "grid", "name": "g", "shape": [2, 3],
              "obstacles": ["..#", "..."], "base": [1, 0]}  # fmt: skip
    drawing = Drawing(header)
    frame = {"tick": 4, "robots": {"a": [0, 1]}, "marks": [-1, 3, -1, -1, -1, -1],
             "colours": [0, 0, 0, 0, 0, 0], "resources": [0, 0, 0, 0, 0, 2],
             "seen": [1, 1, 0, 0, 0, 0]}  # fmt: skip
    out = _by_path(drawing.frame(frame))
    image = np.asarray(out["grid/cells"][0].buffer.pa_array.to_pylist()[0], dtype=np.uint8)
    cells = image.reshape(2, 3, 3)
    assert cells[0, 2].tolist() == [60, 60, 60]  # the obstacle
    assert cells[1, 0].tolist() == [240, 190, 40]  # the base
    assert cells[1, 2].tolist() == [60, 170, 60]  # a resource
    assert _positions(out["robots"][0]) == [[1.5, 0.5]]  # column 1, row 0: cell centres
    assert out["grid/marks"][0].labels.pa_array.to_pylist() == ["3"]
    assert "grid/cells" not in _by_path(drawing.frame(frame))  # unchanged: not sent again


def _recording(path: Path, n: int = 30) -> None:
    header = {k: v for k, v in HEADER.items() if k != "kind"}
    lines = [json.dumps(header)]
    for t in range(n):
        lines.append(json.dumps({"type": "tick", **_frame(t, (0.5 + 0.1 * t, 1.0, 0.0))}))
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("suffix", [".jsonl", ".mcap"])
def test_a_replay_saved_as_rrd_reads_back(tmp_path: Path, suffix: str) -> None:
    """A JSON-lines recording, and the same exported as MCAP (``mover replay run.jsonl --out
    run.mcap``), replayed to a ``.rrd``: the same entities, ticks and poses."""
    from rerun.chunk import RrdReader

    rec, rrd = tmp_path / "run.jsonl", tmp_path / "run.rrd"
    _recording(rec)
    if suffix == ".mcap":
        pytest.importorskip("mcap_ros2", reason="the mcap extra is not installed")
        rec, jsonl = tmp_path / "run.mcap", rec
        assert main(["replay", str(jsonl), "--out", str(rec)]) == 0
    assert main(["replay", str(rec), "--out", str(rrd)]) == 0
    reader = RrdReader(rrd)
    (store,) = reader.recordings()
    assert store.application_id == "mover"
    ticks: list[int] = []
    xs: dict[int, float] = {}
    paths = set()
    for chunk in reader.stream().to_chunks():
        paths.add(chunk.entity_path)
        if chunk.entity_path != "/robots":
            continue
        assert {"sim_time", "tick"} <= set(chunk.timeline_names)
        batch = chunk.to_record_batch()
        for tick, pos in zip(
            batch.column("tick").to_pylist(),
            batch.column("Points2D:positions").to_pylist(),
            strict=True,
        ):
            ticks.append(tick)
            xs[tick] = pos[0][0]  # ann's x
    assert sorted(ticks) == list(range(30))
    assert xs[29] == pytest.approx(0.5 + 2.9)
    assert {"/arena", "/obstacles/circles", "/targets", "/boxes", "/trails/ann/0"} <= paths
