"""A world's scene and state frames as rerun entities: what ``mover view`` and ``mover replay``
draw.

One :class:`Drawing` per world session turns the scene (``view.scene``, or a recording's header)
and each state frame (a ``world/state`` snapshot, a recording's tick line, a grid's
``view.frame``) into a list of :data:`Entity` — ``(path, archetype, static)`` — which
:func:`log_frame` logs at the frame's time on the ``sim_time`` (seconds) and ``tick``
timelines. Keeping the conversion apart from the stream lets tests check it without a viewer.

Rerun's 2D views have y pointing down, the world has it up: the pymunk world is drawn with
``y → height - y`` and headings negated, so that it looks as its PNG does. A grid is drawn in
cell units, row 0 at the top, as its text rendering is.

Costs, per frame: one batch per kind (robots, headings, LEDs, boxes), plus one short trail
piece per robot that moved. A trail is kept in pieces of :data:`TRAIL_PIECE` points (a piece is
logged while it grows, then left alone), at most :data:`TRAIL_PIECES` pieces per robot (older
ones are cleared), so a long run costs memory in proportion to its length, bounded.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from sim_hw.continuous._record import PALETTE, box_corners

Entity = tuple[str, Any, bool]
"""An entity path, the archetype to log there, and whether it is static (timeless)."""

TRAIL_PIECE = 64
"""Points per trail piece."""

TRAIL_PIECES = 64
"""Trail pieces kept per robot (older ones are cleared)."""

TRAIL_STEP = 0.02
"""A trail gains a point once its robot moved this far (m; cells in a grid)."""

MAX_LABELS = 2000
"""Floor values labelled at most per grid frame (a larger floor is drawn without them)."""

GREY, DARK, WALL = (115, 115, 115), (50, 50, 50), (20, 20, 20)
EYEBOT = (70, 110, 200)
AREA_COLOURS = {"source": (40, 160, 60), "target": (200, 30, 30)}


def rgb(colour: str) -> tuple[int, int, int]:
    """``#rrggbb`` as three bytes."""
    return (int(colour[1:3], 16), int(colour[3:5], 16), int(colour[5:7], 16))


def led_colour(led: str) -> tuple[int, int, int] | None:
    """The colour a robot's LED shows: a colour name or ``#rrggbb``; a message (``mark:<id>``,
    any other text) shows white; ``""`` is off (None)."""
    if not led:
        return None
    from matplotlib.colors import to_rgb

    try:
        r, g, b = to_rgb(led)
    except ValueError:
        return (255, 255, 255)
    return (round(r * 255), round(g * 255), round(b * 255))


def circle(center: Sequence[float], radius: float, n: int = 32) -> list[tuple[float, float]]:
    """A closed polygon of ``n`` sides around ``center``."""
    return [
        (center[0] + radius * math.cos(a), center[1] + radius * math.sin(a))
        for a in np.linspace(0.0, 2.0 * math.pi, n + 1)
    ]


class Drawing:
    """The entities of one world session (see the module).

    ``names`` fixes the colours of robots known in advance (sorted, as the PNG has them);
    robots seen later get the next colours. ``links`` (m, or cells) draws a line between every
    two robots within that distance (the radio's reach, say).
    """

    def __init__(
        self,
        header: Mapping[str, Any],
        *,
        names: Iterable[str] = (),
        links: float | None = None,
    ) -> None:
        self.header = header
        self.grid = header.get("kind") == "grid"
        self.width: float
        self.height: float
        if self.grid:
            self.height, self.width = (int(v) for v in header["shape"])
        else:
            self.width, self.height = (float(v) for v in header["size"])
        self.links = links
        self.colours: dict[str, tuple[int, int, int]] = {}
        for name in sorted(set(names) | {k for k in header.get("radii", {}) if k != "*"}):
            self.colour(name)
        self._trails: dict[str, list[list[tuple[float, float]]]] = {}
        self._cleared: dict[str, int] = {}
        self._marked: frozenset[str] | None = None
        self._cells: bytes | None = None

    # -- helpers ----------------------------------------------------------------------------

    def colour(self, name: str) -> tuple[int, int, int]:
        """The colour of robot ``name`` (a new one gets the next free colour)."""
        if name not in self.colours:
            self.colours[name] = rgb(PALETTE[len(self.colours) % len(PALETTE)])
        return self.colours[name]

    def xy(self, x: float, y: float) -> tuple[float, float]:
        """A world point in the view's frame (y down)."""
        return (float(x), self.height - float(y))

    def bounds(self) -> rrb.VisualBounds2D:
        """What the view shows: the arena (or grid) and a small margin."""
        m = 0.3 if not self.grid else 0.5
        return rrb.VisualBounds2D(x_range=[-m, self.width + m], y_range=[-m, self.height + m])

    def blueprint(self, *, live: bool = True) -> rrb.Blueprint:
        """One 2D view of the world, the time panel open (following the newest data when
        ``live``, else playing from the start), the side panels folded."""
        name = str(self.header.get("name", "world"))
        return rrb.Blueprint(
            rrb.Spatial2DView(origin="/", name=name, visual_bounds=self.bounds()),
            rrb.BlueprintPanel(state="collapsed"),
            rrb.SelectionPanel(state="collapsed"),
            rrb.TimePanel(
                state="expanded",
                timeline="tick" if self.grid else "sim_time",
                play_state="following" if live else "playing",
            ),
        )

    # -- the static scene -------------------------------------------------------------------

    def scene(self) -> list[Entity]:
        """The static entities: the arena and what never moves (see the module)."""
        return self._grid_scene() if self.grid else self._continuous_scene()

    def _continuous_scene(self) -> list[Entity]:
        h = self.header
        out: list[Entity] = [self._arena(0.03)]
        discs = [o for o in h.get("obstacles", []) if o["shape"] == "circle"]
        if discs:
            out.append(self._discs("obstacles/circles", discs, GREY, 2.0))
        strips, radii = [], []
        for o in h.get("obstacles", []):
            if o["shape"] == "box":
                strips.append(self._outline(o["center"], o["size"], o["angle"]))
                radii.append(0.02)
            elif o["shape"] == "segment":
                strips.append([self.xy(*o["a"]), self.xy(*o["b"])])
                radii.append(max(float(o.get("radius", 0.0)), 0.02))
        if strips:
            out.append(
                (
                    "obstacles/outlines",
                    rr.LineStrips2D(strips, radii=radii, colors=GREY, draw_order=2.0),
                    True,
                )
            )
        ims = h.get("immovables", [])
        round_ims = [i for i in ims if i.get("shape") == "circle"]
        if round_ims:
            out.append(self._discs("immovables/circles", round_ims, DARK, 2.0, labels=True))
        square = [i for i in ims if i.get("shape") != "circle"]
        if square:
            out.append(
                (
                    "immovables/outlines",
                    rr.LineStrips2D(
                        [self._outline(i["center"], i["size"], i["angle"]) for i in square],
                        radii=0.03,
                        colors=DARK,
                        labels=[i["id"] for i in square],
                        draw_order=2.0,
                    ),
                    True,
                )
            )
        markers = h.get("markers", [])
        if markers:
            out.append(
                (
                    "targets",
                    rr.LineStrips2D(
                        [[self.xy(*p) for p in circle(m["center"], m["radius"])] for m in markers],
                        radii=0.015,
                        colors=(200, 30, 30),
                        labels=[m["id"] for m in markers],
                        draw_order=3.0,
                    ),
                    True,
                )
            )
        return out + self._ceiling()

    def _ceiling(self) -> list[Entity]:
        """The source and target areas, and the eye-bots on the ceiling: each one's disc of
        view on the floor, and its reference direction θ0 (a red stroke from the centre)."""
        out: list[Entity] = []
        h = self.header
        areas = h.get("areas") or []
        if areas:
            strips = [[self.xy(*p) for p in circle(a["center"], a["radius"])] for a in areas]
            out.append(
                (
                    "areas",
                    rr.LineStrips2D(
                        strips,
                        radii=0.03,
                        colors=[AREA_COLOURS.get(a["id"], GREY) for a in areas],
                        labels=[a["id"] for a in areas],
                        draw_order=1.5,
                    ),
                    True,
                )
            )
        eyes = h.get("eyebots") or []
        if not eyes:
            return out
        views = [[self.xy(*p) for p in circle(e["center"], e["view"])] for e in eyes]
        out.append(
            (
                "eyebots/view",
                rr.LineStrips2D(views, radii=0.01, colors=EYEBOT, draw_order=1.6),
                True,
            )
        )
        out.append(
            (
                "eyebots/theta0",
                rr.LineStrips2D(
                    [
                        [
                            self.xy(*e["center"]),
                            self.xy(
                                e["center"][0] + 0.3 * math.cos(e["heading"]),
                                e["center"][1] + 0.3 * math.sin(e["heading"]),
                            ),
                        ]
                        for e in eyes
                    ],
                    radii=0.02,
                    colors=(220, 40, 40),
                    labels=[e["id"] for e in eyes],
                    draw_order=6.0,
                ),
                True,
            )
        )
        return out

    def _discs(
        self,
        path: str,
        items: list[Mapping[str, Any]],
        colour: Any,
        order: float,
        *,
        labels: bool = False,
    ) -> Entity:
        return (
            path,
            rr.Points2D(
                [self.xy(*i["center"]) for i in items],
                radii=[float(i["radius"]) for i in items],
                colors=colour,
                labels=[i["id"] for i in items] if labels else None,
                draw_order=order,
            ),
            True,
        )

    def _outline(
        self, center: Sequence[float], size: Sequence[float], angle: float
    ) -> list[tuple[float, float]]:
        corners = box_corners(center, size, angle)
        return [self.xy(*p) for p in [*corners, corners[0]]]

    def _grid_scene(self) -> list[Entity]:
        return [self._arena(0.05)]

    def _arena(self, radius: float) -> Entity:
        """The arena's bounding walls, drawn ``radius`` thick."""
        w, ht = self.width, self.height
        return (
            "arena",
            rr.LineStrips2D(
                [[(0, 0), (w, 0), (w, ht), (0, ht), (0, 0)]],
                radii=radius,
                colors=WALL,
                draw_order=1.0,
            ),
            True,
        )

    # -- frames -----------------------------------------------------------------------------

    def frame(self, frame: Mapping[str, Any]) -> list[Entity]:
        """The entities of one state frame (robots, boxes, targets marked, trails, links)."""
        return self._grid_frame(frame) if self.grid else self._continuous_frame(frame)

    def _continuous_frame(self, frame: Mapping[str, Any]) -> list[Entity]:
        robots = frame.get("robots") or {}
        radii = self.header.get("radii", {})
        default = float(radii.get("*", 0.15))
        names = sorted(robots)
        pos = [self.xy(robots[n][0], robots[n][1]) for n in names]
        rad = [float(radii.get(n, default)) for n in names]
        heads = [
            [p, (p[0] + r * math.cos(robots[n][2]), p[1] - r * math.sin(robots[n][2]))]
            for n, p, r in zip(names, pos, rad, strict=True)
        ]
        lit: list[tuple[tuple[float, float], float, tuple[int, int, int]]] = []
        for n, p, r in zip(names, pos, rad, strict=True):
            led = led_colour(str(robots[n][3]) if len(robots[n]) > 3 else "")
            if led is not None:
                lit.append((p, r, led))
        out: list[Entity] = [
            (
                "robots",
                rr.Points2D(
                    pos,
                    radii=rad,
                    colors=[self.colour(n) for n in names],
                    labels=names,
                    draw_order=6.0,
                ),
                False,
            ),
            (
                "robots/heading",
                rr.LineStrips2D(heads, radii=0.025, colors=(20, 20, 20), draw_order=7.0),
                False,
            ),
            (
                "robots/led",
                rr.Points2D(
                    [x[0] for x in lit],
                    radii=[0.4 * x[1] for x in lit],
                    colors=[x[2] for x in lit],
                    draw_order=8.0,
                ),
                False,
            ),
        ]
        boxes = frame.get("boxes") or {}
        sizes = {b["id"]: b["size"] for b in self.header.get("boxes", [])}
        shown = [b for b in sorted(boxes) if b in sizes]
        if shown:
            out.append(
                (
                    "boxes",
                    rr.LineStrips2D(
                        [self._outline(boxes[b][:2], sizes[b], boxes[b][2]) for b in shown],
                        radii=0.03,
                        colors=(140, 80, 20),
                        labels=shown,
                        draw_order=5.0,
                    ),
                    False,
                )
            )
        out += self._marked_targets(frame.get("marked") or {})
        for n, p in zip(names, pos, strict=True):
            out += self._trail(n, p, TRAIL_STEP)
        out += self._links(names, pos)
        return out

    def _marked_targets(self, marked: Mapping[str, Any]) -> list[Entity]:
        now = frozenset(marked)
        if now == self._marked:
            return []
        self._marked = now
        hit = [m for m in self.header.get("markers", []) if m["id"] in now]
        return [
            (
                "targets/marked",
                rr.Points2D(
                    [self.xy(*m["center"]) for m in hit],
                    radii=[float(m["radius"]) for m in hit],
                    colors=(230, 120, 120, 160),
                    draw_order=3.5,
                ),
                False,
            )
        ]

    def _trail(self, name: str, p: tuple[float, float], step: float) -> list[Entity]:
        pieces = self._trails.setdefault(name, [[p]])
        last = pieces[-1][-1]
        if math.dist(last, p) < step and len(pieces[-1]) > 1:
            return []
        if math.dist(last, p) < step:
            return []
        if len(pieces[-1]) >= TRAIL_PIECE:
            pieces.append([last])
        pieces[-1].append(p)
        k = len(pieces) - 1 + self._cleared.get(name, 0)
        out: list[Entity] = [
            (
                f"trails/{name}/{k}",
                rr.LineStrips2D(
                    [pieces[-1]],
                    radii=0.012 if not self.grid else 0.06,
                    colors=self.colour(name),
                    draw_order=4.0,
                ),
                False,
            )
        ]
        if len(pieces) > TRAIL_PIECES:
            pieces.pop(0)
            gone = self._cleared.get(name, 0)
            self._cleared[name] = gone + 1
            out.append((f"trails/{name}/{gone}", rr.Clear(recursive=False), False))
        return out

    def _links(self, names: Sequence[str], pos: Sequence[tuple[float, float]]) -> list[Entity]:
        if self.links is None:
            return []
        pairs = [
            [pos[i], pos[j]]
            for i in range(len(pos))
            for j in range(i + 1, len(pos))
            if math.dist(pos[i], pos[j]) <= self.links
        ]
        return [
            (
                "links",
                rr.LineStrips2D(pairs, radii=0.01, colors=(90, 160, 90), draw_order=5.5),
                False,
            )
        ]

    def _grid_frame(self, frame: Mapping[str, Any]) -> list[Entity]:
        out: list[Entity] = []
        h, w = int(self.height), int(self.width)
        n = h * w
        marks = list(frame.get("marks") or [-1] * n)[:n]
        colours = list(frame.get("colours") or [0] * n)[:n]
        resources = list(frame.get("resources") or [0] * n)[:n]
        seen = list(frame.get("seen") or [0] * n)[:n]
        image = self._grid_image(marks, colours, resources, seen)
        if image.tobytes() != self._cells:
            self._cells = image.tobytes()
            out.append(("grid/cells", rr.Image(image, draw_order=0.0), False))
        values = [(i, v) for i, v in enumerate(marks) if v >= 0]
        if len(values) <= MAX_LABELS:
            out.append(
                (
                    "grid/marks",
                    rr.Points2D(
                        [(i % w + 0.5, i // w + 0.5) for i, _ in values],
                        radii=0.02,
                        colors=(40, 40, 40),
                        labels=[str(v) for _, v in values],
                        draw_order=2.0,
                    ),
                    False,
                )
            )
        robots = frame.get("robots") or {}
        names = sorted(robots)
        pos = [(float(robots[r][1]) + 0.5, float(robots[r][0]) + 0.5) for r in names]
        out.append(
            (
                "robots",
                rr.Points2D(
                    pos,
                    radii=0.35,
                    labels=names,
                    colors=[self.colour(r) for r in names],
                    draw_order=6.0,
                ),
                False,
            )
        )
        for r, p in zip(names, pos, strict=True):
            out += self._trail(r, p, 0.5)
        out += self._links(names, pos)
        return out

    def _grid_image(
        self, marks: list[int], colours: list[int], resources: list[int], seen: list[int]
    ) -> np.ndarray:
        h, w = int(self.height), int(self.width)
        img = np.full((h, w, 3), 245, dtype=np.uint8)
        flat = img.reshape(h * w, 3)
        flat[np.asarray(seen, dtype=bool)] = (222, 232, 250)
        for i, c in enumerate(colours):
            if c:
                r, g, b = rgb(PALETTE[(int(c) - 1) % len(PALETTE)])
                flat[i] = (255 - (255 - r) // 2, 255 - (255 - g) // 2, 255 - (255 - b) // 2)
        for i, q in enumerate(resources):
            if q > 0:
                flat[i] = (60, 170, 60)
        rows = self.header.get("obstacles", [])
        for r, row in enumerate(rows[:h]):
            for c, ch in enumerate(row[:w]):
                if ch == "#":
                    img[r, c] = (60, 60, 60)
        base = self.header.get("base")
        if base is not None and 0 <= base[0] < h and 0 <= base[1] < w:
            img[base[0], base[1]] = (240, 190, 40)
        return img


def frame_time(frame: Mapping[str, Any]) -> tuple[int, float | None]:
    """A frame's tick and simulated time (None for a grid: it counts rounds only)."""
    t = frame.get("t")
    return int(frame.get("tick", 0)), None if t is None else float(t)


def log_entities(rec: rr.RecordingStream, entities: Iterable[Entity]) -> None:
    """Log ``entities`` on ``rec`` at its current time (static ones timeless)."""
    for path, archetype, static in entities:
        rec.log(path, archetype, static=static)


def log_frame(rec: rr.RecordingStream, drawing: Drawing, frame: Mapping[str, Any]) -> None:
    """Log one state frame at its time on the ``tick`` and ``sim_time`` timelines."""
    tick, t = frame_time(frame)
    rec.set_time("tick", sequence=tick)
    if t is not None:
        rec.set_time("sim_time", duration=t)
    log_entities(rec, drawing.frame(frame))
