"""Recording a run to JSON lines, reading it back, and drawing its trajectories.

A recording starts with a header line (the arena: size, obstacles, objects, markers, robot radii,
seed) and has one line per recorded tick: the true poses of robots and boxes and the commands
applied. Commands make a recording a replay script too: re-running the world from the same seed
with the logged commands reproduces it (docs/physics.md, determinism). The header is also what a
world tells a viewer about its scene (``sim_hw.view``), so that live and replayed views draw the
same.

A world that is killed mid-write leaves its last line cut short: :func:`read_recording` keeps
every complete line before it and says so in one warning.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import IO, Any

from ._world import World

log = logging.getLogger("sim_hw.record")

MAX_LINE = 64 * 1024 * 1024
"""The longest line a recording may have (bytes); a longer one is not a recording's."""

PALETTE = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#17becf",
    "#bcbd22",
    "#7f7f7f",
)
"""Track colours (matplotlib's tab10, cyan before olive): robots in name order, then boxes."""


def track_colours(names: Iterable[str]) -> dict[str, str]:
    """A colour per name, in sorted order over :data:`PALETTE` (the PNG and the viewer agree)."""
    return {n: PALETTE[i % len(PALETTE)] for i, n in enumerate(sorted(set(names)))}


def scene_header(world: World) -> dict[str, Any]:
    """The static scene of ``world``: the header line of a recording and a viewer's scene."""
    spec = world.spec
    radii = {"*": spec.robot.radius, **{rid: r.radius for rid, r in spec.robots.items()}}
    radii.update({rid: r.parts.spec.radius for rid, r in world.robots.items()})
    return {
        "type": "header",
        "name": spec.name,
        "size": list(spec.size),
        "seed": world.seed,
        "obstacles": [asdict(o) for o in spec.obstacles],
        "boxes": [asdict(b) for b in spec.boxes],
        "immovables": [asdict(i) for i in spec.immovables],
        "markers": [asdict(m) for m in spec.markers],
        "radii": radii,
        "eyebots": [asdict(e) for e in spec.eyebots],
        "areas": [asdict(a) for a in spec.areas],
    }


class JsonLinesSink:
    """Writes records as JSON lines: one of the two formats of a :class:`Recorder` (the other
    is MCAP, :class:`sim_hw.continuous._mcap.McapSink`)."""

    sensors = False  # a tick's sensor readings are not kept (the commands replay them)
    phases = False  # nor the phases: they arrive by the wall clock, and a seeded run must
    # record the same bytes whatever the scheduling (docs/reproducible-runs.md)

    def __init__(self, path: str | Path) -> None:
        self._file: IO[str] = Path(path).open("w", encoding="utf-8")  # noqa: SIM115

    def write(self, record: Mapping[str, Any]) -> None:
        """Write one record as a line."""
        self._file.write(json.dumps(record, separators=(",", ":")) + "\n")

    def close(self) -> None:
        """Flush and close the file."""
        if not self._file.closed:
            self._file.close()


def open_sink(path: str | Path) -> Any:
    """The writer of ``path``'s format, which its suffix picks: ``.mcap`` is MCAP with ROS 2
    messages (the ``mcap`` extra), anything else JSON lines."""
    if Path(path).suffix == ".mcap":
        from ._mcap import McapSink

        return McapSink(path)
    return JsonLinesSink(path)


class Recorder:
    """Writes ``world``'s run to ``path``, every ``every``-th tick: a hook on the door's
    ``on_tick`` (``server.door.on_tick.append(recorder)``). The suffix picks the format
    (:func:`open_sink`)."""

    def __init__(self, path: str | Path, world: World, every: int = 1) -> None:
        self.path = Path(path)
        self.world = world
        self.every = max(1, every)
        self._sink = open_sink(self.path)
        self._phases: dict[str, list[str]] = {}
        self._sink.write(scene_header(world))
        self._write({"type": "tick", **world.snapshot(), "commands": {}})

    def __call__(self, commands: Mapping[str, Mapping[str, Any]]) -> None:
        world = self.world
        if world.tick % self.every == 0:
            self._write({"type": "tick", **world.snapshot(), "commands": dict(commands)})

    def phase(self, member: str, phase: str) -> None:
        """``member``'s program reported ``phase``: written with the next recorded tick (its
        ``phases``, in the order heard; see :mod:`sim_hw.continuous._phases`). Only a sink that
        keeps phases (MCAP) gets them."""
        if self._sink.phases:
            self._phases.setdefault(member, []).append(phase)

    def _write(self, record: dict[str, Any]) -> None:
        if self._phases:
            record["phases"], self._phases = self._phases, {}
        if self._sink.sensors:
            record["sensors"] = {rid: self._sensors(rid) for rid in record["robots"]}
        self._sink.write(record)

    def _sensors(self, rid: str) -> dict[str, Any]:
        robot = self.world.robots[rid]
        got = robot.readings
        sonar = robot.parts.spec.sonar
        return {
            "odom": got.get("odom"),
            "sonar": got.get("sonar"),
            "angles": list(robot.angles),
            "range_max": sonar.max_range if sonar else 0.0,
        }

    def close(self) -> None:
        """Write the phases heard since the last recorded tick (a lock-step world whose robots
        are idle does not tick: a run's last phase comes after its last tick) with the world
        as it is, then flush and close the file."""
        try:
            if self._phases:
                self._write({"type": "tick", **self.world.snapshot(), "commands": {}})
        finally:
            self._sink.close()


def read_recording(path: str | Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The header and the tick records of a recording.

    A last line cut short (the world was killed while writing it) is left out with one warning;
    any other line that is not a record is a ValueError naming it. A ``.mcap`` file is read as
    MCAP (:func:`sim_hw.continuous._mcap.read_mcap`).
    """
    if Path(path).suffix == ".mcap":
        from ._mcap import read_mcap

        return read_mcap(path)
    header: dict[str, Any] | None = None
    ticks: list[dict[str, Any]] = []
    cut: tuple[int, str] | None = None  # a line that did not parse: fine only if it is the last
    with Path(path).open(encoding="utf-8", errors="replace") as f:
        for n, line in enumerate(iter(lambda: f.readline(MAX_LINE), ""), 1):
            if not line.strip():
                continue
            if cut is not None:
                raise ValueError(f"{path}: line {cut[0]}: not JSON: {cut[1]}")
            if not line.endswith("\n") and len(line) >= MAX_LINE:
                raise ValueError(f"{path}: line {n}: longer than {MAX_LINE} bytes")
            try:
                record = json.loads(line)
            except json.JSONDecodeError as exc:
                cut = (n, exc.msg)
                continue
            kind = record.get("type") if isinstance(record, dict) else None
            if kind == "header":
                header = record
            elif kind == "tick":
                ticks.append(record)
            else:
                raise ValueError(f"{path}: line {n}: not a recording record")
    if header is None:
        raise ValueError(f"{path}: no header line: not a recording")
    if cut is not None:
        last = f"tick {ticks[-1].get('tick')}" if ticks else "the header"
        log.warning(
            "%s: line %d is cut short (the world stopped mid-write): replaying up to %s",
            path,
            cut[0],
            last,
        )
    return header, ticks


def run_end(ticks: Sequence[Mapping[str, Any]]) -> float:
    """The simulated time the run ended: the last tick in which a robot or a box moved (a
    recording goes on while a world waits with nothing moving); else the last tick's time."""
    end = 0.0
    before: tuple[Any, Any] | None = None
    for tick in ticks:
        now = (_places(tick.get("robots", {})), _places(tick.get("boxes", {})))
        if before is not None and now != before:
            end = float(tick.get("t", 0.0))
        before = now
    if end == 0.0 and ticks:
        end = float(ticks[-1].get("t", 0.0))
    return end


def _places(poses: Mapping[str, Sequence[Any]]) -> dict[str, tuple[float, float, float]]:
    return {k: (round(p[0], 4), round(p[1], 4), round(p[2], 3)) for k, p in poses.items()}


def plot_recording(path: str | Path, out: str | Path) -> None:
    """Draw the arena and every robot's and box's trajectory to a PNG.

    Obstacles (solid grey) and immovables (hatched, named) are drawn as their shapes (circles as
    circles), each kind in the legend; each track has one
    colour for its line, its start (a hollow square) and its end (a dot), as in the legend;
    boxes are outlined where they started (dashed) and ended; axes are in metres; the title
    gives the time the run ended (see :func:`run_end`).
    """
    header, ticks = read_recording(path)
    fig = draw_recording(header, ticks)
    try:
        fig.savefig(out, dpi=100)
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


def draw_recording(header: Mapping[str, Any], ticks: Sequence[Mapping[str, Any]]) -> Any:
    """The matplotlib figure of :func:`plot_recording` (for tests and for other formats)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch, Polygon, Rectangle

    w, h = header["size"]
    fig, ax = plt.subplots(figsize=(7.5, max(3.0, 7.5 * h / w) if w else 7.5))
    ax.add_patch(Rectangle((0, 0), w, h, fill=False, lw=2, label="_arena"))
    for ob in header.get("obstacles", []):
        if ob["shape"] == "circle":
            ax.add_patch(Circle(ob["center"], ob["radius"], color="0.45", label="_obstacle"))
        elif ob["shape"] == "box":
            corners = box_corners(ob["center"], ob["size"], ob["angle"])
            ax.add_patch(Polygon(corners, color="0.45", label="_obstacle"))
        else:
            ax.plot([ob["a"][0], ob["b"][0]], [ob["a"][1], ob["b"][1]], color="0.45", lw=3)
    immovable: dict[str, Any] = {"fc": "0.85", "ec": "0.1", "hatch": "////", "lw": 1.2}
    for im in header.get("immovables", []):
        if im.get("shape") == "circle":
            patch: Any = Circle(im["center"], im["radius"], label="_immovable", **immovable)
        else:
            corners = box_corners(im["center"], im["size"], im["angle"])
            patch = Polygon(corners, label="_immovable", **immovable)
        ax.add_patch(patch)
        ax.annotate(
            im["id"], im["center"], fontsize=7, ha="center", va="center", backgroundcolor="w"
        )
    marked = ticks[-1].get("marked", {}) if ticks else {}
    for mk in header.get("markers", []):
        hit = mk["id"] in marked
        ax.add_patch(
            Circle(mk["center"], mk["radius"], fill=hit, alpha=0.5 if hit else 1.0, ls="--")
        )
        ax.annotate(mk["id"], mk["center"], fontsize=7, ha="center", va="center")
    robots = _tracks(ticks, "robots")
    boxes = _tracks(ticks, "boxes")
    known = {k for k in header.get("radii", {}) if k != "*"}  # the world file's: as the viewer
    colours = {r: c for r, c in track_colours(known | robots.keys()).items() if r in robots}
    spare = PALETTE[len(known | robots.keys()) % len(PALETTE) :] + PALETTE
    colours.update({b: spare[i % len(spare)] for i, b in enumerate(sorted(boxes))})
    sizes = {b["id"]: b["size"] for b in header.get("boxes", [])}
    labelled = len(robots) + len(boxes) <= 12
    for key, tracks in (("robot", robots), ("box", boxes)):
        for ident, pts in sorted(tracks.items()):
            colour = colours[ident]
            xs = [p[0] for p in pts]
            ys = [p[1] for p in pts]
            lw = 2.5 if key == "box" else 1.2
            ax.plot(xs, ys, "-", color=colour, lw=lw, label=ident if labelled else None)
            ax.plot(xs[:1], ys[:1], "s", mfc="none", mec=colour, ms=6, label="_start")
            ax.plot(xs[-1:], ys[-1:], "o", color=colour, ms=5, label="_end")
            if key == "box" and ident in sizes:
                for pose, ls in ((pts[0], "--"), (pts[-1], "-")):
                    corners = box_corners(pose[:2], sizes[ident], pose[2])
                    ax.add_patch(Polygon(corners, fill=False, ec=colour, ls=ls, lw=1.2))
    ax.set_xlim(-0.2, w + 0.2)
    ax.set_ylim(-0.2, h + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    t_run = run_end(ticks)
    t_rec = float(ticks[-1].get("t", 0.0)) if ticks else 0.0
    title = f"{header.get('name', 'world')} — run ended at {t_run:.1f} s simulated"
    if t_rec > t_run + 1e-6:
        title += f" (recorded to {t_rec:.1f} s)"
    ax.set_title(title, fontsize=10)
    handles, _ = ax.get_legend_handles_labels()
    if handles:
        handles += [
            Line2D([], [], ls="", marker="s", mfc="none", mec="0.3", label="start"),
            Line2D([], [], ls="", marker="o", color="0.3", label="end"),
        ]
        if header.get("obstacles"):
            handles.append(Patch(color="0.45", label="obstacle"))
        if header.get("immovables"):
            handles.append(Patch(label="immovable object", **immovable))
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig


def _tracks(ticks: Sequence[Mapping[str, Any]], key: str) -> dict[str, list[Sequence[float]]]:
    tracks: dict[str, list[Sequence[float]]] = {}
    for tick in ticks:
        for ident, pose in tick.get(key, {}).items():
            tracks.setdefault(ident, []).append(pose)
    return tracks


def box_corners(
    center: Sequence[float], size: Sequence[float], angle: float
) -> list[tuple[float, float]]:
    """The four corners of a ``size`` box at ``center`` turned by ``angle`` (counter-clockwise)."""
    cx, cy = center[0], center[1]
    hw, hh = size[0] / 2, size[1] / 2
    c, s = math.cos(angle), math.sin(angle)
    return [
        (cx + c * x - s * y, cy + s * x + c * y)
        for x, y in ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))
    ]
