"""Recording a run to JSON lines, reading it back, and drawing its trajectories.

A recording starts with a header line (the arena: size, obstacles, objects, markers, seed) and
has one line per recorded tick: the true poses of robots and boxes and the commands applied.
Commands make a recording a replay script too: re-running the world from the same seed with the
logged commands reproduces it (docs/physics.md, determinism).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import IO, Any

from ._world import World


class Recorder:
    """An ``on_tick`` hook for :class:`WorldServer` that writes every ``every``-th tick."""

    def __init__(self, path: str | Path, world: World, every: int = 1) -> None:
        self.path = Path(path)
        self.every = max(1, every)
        self._file: IO[str] = self.path.open("w", encoding="utf-8")
        spec = world.spec
        header = {
            "type": "header",
            "name": spec.name,
            "size": list(spec.size),
            "seed": world.seed,
            "obstacles": [asdict(o) for o in spec.obstacles],
            "boxes": [asdict(b) for b in spec.boxes],
            "immovables": [asdict(i) for i in spec.immovables],
            "markers": [asdict(m) for m in spec.markers],
        }
        self._write(header)
        self._write({"type": "tick", **world.snapshot(), "commands": {}})

    def __call__(self, world: World, commands: Mapping[str, Mapping[str, Any]]) -> None:
        if world.tick % self.every == 0:
            self._write({"type": "tick", **world.snapshot(), "commands": dict(commands)})

    def _write(self, record: dict[str, Any]) -> None:
        self._file.write(json.dumps(record, separators=(",", ":")) + "\n")

    def close(self) -> None:
        """Flush and close the file."""
        if not self._file.closed:
            self._file.close()


def read_recording(path: str | Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The header and the tick records of a recording."""
    header: dict[str, Any] | None = None
    ticks: list[dict[str, Any]] = []
    with Path(path).open(encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{path}: line {n}: not JSON: {exc.msg}") from None
            kind = record.get("type") if isinstance(record, dict) else None
            if kind == "header":
                header = record
            elif kind == "tick":
                ticks.append(record)
            else:
                raise ValueError(f"{path}: line {n}: not a recording record")
    if header is None:
        raise ValueError(f"{path}: no header line: not a recording")
    return header, ticks


def plot_recording(path: str | Path, out: str | Path) -> None:
    """Draw the arena and every robot's and box's trajectory to a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon, Rectangle

    header, ticks = read_recording(path)
    w, h = header["size"]
    fig, ax = plt.subplots(figsize=(7, 7 * h / w if w else 7))
    ax.add_patch(Rectangle((0, 0), w, h, fill=False, lw=2))
    for ob in header["obstacles"]:
        if ob["shape"] == "circle":
            ax.add_patch(Circle(ob["center"], ob["radius"], color="0.4"))
        elif ob["shape"] == "box":
            ax.add_patch(Polygon(_corners(ob["center"], ob["size"], ob["angle"]), color="0.4"))
        else:
            ax.plot([ob["a"][0], ob["b"][0]], [ob["a"][1], ob["b"][1]], color="0.4", lw=3)
    for im in header["immovables"]:
        ax.add_patch(Polygon(_corners(im["center"], im["size"], im["angle"]), color="0.2"))
    for mk in header["markers"]:
        ax.add_patch(Circle(mk["center"], mk["radius"], fill=False, ls="--"))
        ax.annotate(mk["id"], mk["center"], fontsize=7, ha="center")
    for key, style in (("robots", "-"), ("boxes", "-")):
        tracks: dict[str, list[tuple[float, float]]] = {}
        for tick in ticks:
            for ident, pose in tick.get(key, {}).items():
                tracks.setdefault(ident, []).append((pose[0], pose[1]))
        for ident, pts in sorted(tracks.items()):
            xs, ys = zip(*pts, strict=True)
            lw = 3 if key == "boxes" else 1
            ax.plot(xs, ys, style, lw=lw, label=ident if len(tracks) <= 12 else None)
            ax.plot(xs[-1:], ys[-1:], "o", ms=3)
    ax.set_xlim(-0.2, w + 0.2)
    ax.set_ylim(-0.2, h + 0.2)
    ax.set_aspect("equal")
    t_end = ticks[-1]["t"] if ticks else 0.0
    ax.set_title(f"{header['name']} — {t_end:.1f} s simulated")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=6, loc="upper right")
    fig.savefig(out, dpi=100)
    plt.close(fig)


def _corners(
    center: Sequence[float], size: Sequence[float], angle: float
) -> list[tuple[float, float]]:
    import math

    cx, cy = center
    hw, hh = size[0] / 2, size[1] / 2
    c, s = math.cos(angle), math.sin(angle)
    return [
        (cx + c * x - s * y, cy + s * x + c * y)
        for x, y in ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))
    ]
