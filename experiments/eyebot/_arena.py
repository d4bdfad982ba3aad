"""The arenas of Ducatelle et al.: the cluttered room of Fig. 1(c) and the double corridor of
Fig. 3, each with its eye-bots, source and target areas, and the eye-bots' shortest-path
directions (the paper's t_s: eye-bots pre-programmed with the shortest path).

The paper gives no dimensions for Fig. 1(c). Chosen here: a 12 × 9 m room; 28 eye-bots on a
triangular lattice 2 m apart (rows √3 m apart), so that every neighbour lies in one of the 12
directions (a square grid's diagonals, at 45°, would not); 2 m is the paper's d, so a foot-bot
that leaves one eye-bot towards a neighbour is under it before d runs out (cones of 0.5 m;
camera discs of 1 m, so neighbours' discs just touch). The target area (1 m radius) is under
the bottom-left eye-bot, the source area under the top-right one; two walls from opposite sides
make an S-shaped way between them, and five posts clutter it. Four lattice places fall on the
walls (x = 4 and 8, the second and fourth rows): no eye-bot is hung there (an eye-bot over a
wall would see and instruct both sides of it), 24 eye-bots in all; the old placement, all 28,
is ``cluttered(over_walls=True)``.

The double corridor is :func:`sim_hw.continuous.double_corridor` (l_r = 20 m, 1 m wide, rooms
3 m deep): eye-bots every 2 m along the middle of each corridor, and over the two rooms on a
grid 2 m wide and 1.5 m deep.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass, field, replace

from sim_hw.continuous import (
    EyeBotSpec,
    MarkerSpec,
    ObstacleSpec,
    WorldSpec,
    corridor_paths,
    double_corridor,
)

AREA = 1.0
"""Radius of the source and target areas (m)."""
SPACING = 2.0
"""Eye-bots' grid spacing (m)."""
VIEW = 1.0
"""Radius of an eye-bot camera's disc on the ground (m)."""
CONE = 0.5
"""Horizontal reach of an eye-bot's broadcast (m)."""
CLEARANCE = 0.15
"""How far from a wall a straight drive between two eye-bots must stay (m)."""


@dataclass(frozen=True)
class Arena:
    """A world, its eye-bots, the source and target areas (centres), and for the double
    corridor the x that divides the left corridor from the right one (None otherwise)."""

    spec: WorldSpec
    eyebots: tuple[EyeBotSpec, ...]
    source: tuple[float, float]
    target: tuple[float, float]
    corridors: tuple[float, float, float] | None = None
    """The double corridor's band: (x dividing left from right, y from, y to)."""
    shortest: dict[str, tuple[float, float]] = field(default_factory=dict)
    """Per eye-bot: (θ_s, θ_t) along the shortest path through the eye-bots (θ0 = 0)."""
    optimum: float = math.nan
    """Length of the shortest way through the eye-bots, from under the target to under the
    source (m)."""
    mirrored: bool = False
    """The double corridor mirrored left to right: its shorter corridor is the left one."""

    def in_source(self, x: float, y: float) -> bool:
        """Whether (x, y) is in the source area."""
        return math.hypot(x - self.source[0], y - self.source[1]) <= AREA

    def in_target(self, x: float, y: float) -> bool:
        """Whether (x, y) is in the target area."""
        return math.hypot(x - self.target[0], y - self.target[1]) <= AREA


def cluttered(over_walls: bool = False) -> Arena:
    """Fig. 1(c), as described in the module docstring (``over_walls``: the old placement,
    eye-bots over the walls kept)."""
    walls = (
        ObstacleSpec("box", center=(4.0, 5.6), size=(0.4, 6.8)),  # from the top, at x = 4
        ObstacleSpec("box", center=(8.0, 3.4), size=(0.4, 6.8)),  # from the bottom, at x = 8
        *(  # clutter: posts in the middle of lattice triangles, off every eye-bot's line
            ObstacleSpec("circle", center=_centroid(j, i), radius=0.25)
            for j, i in ((0, 4), (1, 1), (2, 0), (2, 2), (3, 3))
        ),
    )
    eyes = _lattice("e", rows=5, columns=6)
    if not over_walls:
        eyes = [e for e in eyes if not _inside(walls, e.center)]
    target, source = eyes[0].center, eyes[-1].center
    spec = WorldSpec(
        size=(12.0, 9.0),
        name="eyebot-cluttered",
        obstacles=walls,
        markers=(
            MarkerSpec("target", "source", source, AREA),
            MarkerSpec("target", "target", target, AREA),
        ),
    )
    return _with_shortest(Arena(spec, tuple(eyes), source, target))


def _inside(obstacles: tuple[ObstacleSpec, ...], p: tuple[float, float]) -> bool:
    """Whether ``p`` lies on one of the (axis-aligned) boxes among ``obstacles``."""
    return any(
        ob.shape == "box"
        and abs(p[0] - ob.center[0]) <= ob.size[0] / 2
        and abs(p[1] - ob.center[1]) <= ob.size[1] / 2
        for ob in obstacles
    )


def _centroid(row: int, i: int) -> tuple[float, float]:
    """The middle of the i-th upward triangle of :func:`_lattice` whose base is on ``row``."""
    x = 1.0 + (row % 2) * SPACING / 2 + i * SPACING + SPACING / 2
    return (x, 1.0 + row * SPACING * math.sqrt(3) / 2 + SPACING / math.sqrt(3) / 2)


def _lattice(prefix: str, rows: int, columns: int) -> list[EyeBotSpec]:
    """Eye-bots on a triangular lattice SPACING apart, from (1, 1): rows √3 m apart, every
    other row shifted by half a spacing and one shorter. Its neighbours lie at multiples of
    60°, which the 12 directions (30° apart) can all show."""
    out = []
    for j in range(rows):
        shift = SPACING / 2 if j % 2 else 0.0
        for i in range(columns - (j % 2)):
            x, y = 1.0 + shift + i * SPACING, 1.0 + j * SPACING * math.sqrt(3) / 2
            out.append(EyeBotSpec(f"{prefix}{j}{i:02d}", (x, y), view=VIEW, cone=CONE))
    return out


def corridors(ratio: float, length: float = 20.0, mirrored: bool = False) -> Arena:
    """Fig. 3: two corridors, the right one ``length`` long, the left one ``ratio`` times;
    ``mirrored``: the same arena mirrored left to right (the shorter corridor on the left), to
    tell learning the shorter way from a bias to one side."""
    room = 3.0
    base = double_corridor(length=length, ratio=ratio, width=1.0, room=room)
    h = base.size[1]
    y0, y1 = room, h - room
    marks = {m.id: m.center for m in base.markers}
    source, target = marks["source"], marks["target"]
    # over the rooms: rows 1.5 m apart, columns SPACING apart centred on the source and target
    k = int((source[0] - 0.5) // SPACING)
    lo, hi = source[0] - k * SPACING, source[0] + k * SPACING
    eyes = _grid("s", (lo, room / 2 - 0.75), (hi, room / 2 + 0.75), step=(SPACING, 1.5))
    eyes += _grid("t", (lo, y1 + room / 2 - 0.75), (hi, y1 + room / 2 + 0.75), step=(SPACING, 1.5))
    for name, line in corridor_paths(length=length, ratio=ratio, width=1.0, room=room).items():
        eyes += [
            EyeBotSpec(f"{name[0]}{k:02d}", p, view=VIEW, cone=CONE)
            for k, p in enumerate(_along(line, SPACING))
        ]
    spec = replace(
        base,
        markers=(
            MarkerSpec("target", "source", source, AREA),
            MarkerSpec("target", "target", target, AREA),
        ),
    )
    arena = Arena(spec, tuple(eyes), source, target, (source[0], y0, y1))
    return _with_shortest(_mirror(arena) if mirrored else arena)


def _mirror(arena: Arena) -> Arena:
    """``arena`` mirrored about its vertical middle line (x → w − x)."""
    w = arena.spec.size[0]

    def x(p: tuple[float, float]) -> tuple[float, float]:
        return (w - p[0], p[1])

    assert arena.corridors is not None
    divide, y0, y1 = arena.corridors
    spec = replace(
        arena.spec,
        name=f"{arena.spec.name}-mirrored",
        obstacles=tuple(replace(o, center=x(o.center)) for o in arena.spec.obstacles),
        markers=tuple(replace(m, center=x(m.center)) for m in arena.spec.markers),
    )
    eyes = tuple(replace(e, center=x(e.center)) for e in arena.eyebots)
    return Arena(spec, eyes, x(arena.source), x(arena.target), (w - divide, y0, y1), mirrored=True)


def _along(line: tuple[tuple[float, float], ...], step: float) -> list[tuple[float, float]]:
    """Points every ``step`` along a polyline, the first half a step from its start."""
    points, at = [], step / 2
    travelled = 0.0
    for a, b in itertools.pairwise(line):
        seg = math.dist(a, b)
        while at <= travelled + seg + 1e-9:
            f = (at - travelled) / seg
            points.append((a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])))
            at += step
        travelled += seg
    return points


def _eye(e: EyeBotSpec) -> EyeBotSpec:
    return replace(e, view=VIEW, cone=CONE)


def _grid(
    prefix: str,
    lo: tuple[float, float],
    hi: tuple[float, float],
    step: tuple[float, float] = (SPACING, SPACING),
) -> list[EyeBotSpec]:
    nx = round((hi[0] - lo[0]) / step[0]) + 1
    ny = round((hi[1] - lo[1]) / step[1]) + 1
    return [
        EyeBotSpec(
            f"{prefix}{i:02d}{j:02d}",
            (lo[0] + i * step[0], lo[1] + j * step[1]),
            view=VIEW,
            cone=CONE,
        )
        for j in range(ny)
        for i in range(nx)
    ]


def _with_shortest(arena: Arena) -> Arena:
    """The arena with each eye-bot's shortest-path directions to the source and the target."""
    eyes = {e.id: e.center for e in arena.eyebots}
    edges: dict[str, list[tuple[str, float]]] = {e: [] for e in eyes}
    ids = sorted(eyes)
    reach = SPACING * math.sqrt(2) + 1e-6
    for i, a in enumerate(ids):
        for b in ids[i + 1 :]:
            d = math.dist(eyes[a], eyes[b])
            if d <= reach and _clear(arena.spec.obstacles, eyes[a], eyes[b]):
                edges[a].append((b, d))
                edges[b].append((a, d))
    to_source, far = _dijkstra(edges, [e for e, p in eyes.items() if arena.in_source(*p)])
    to_target, _ = _dijkstra(edges, [e for e, p in eyes.items() if arena.in_target(*p)])
    optimum = min(
        (far[e] for e, p in eyes.items() if arena.in_target(*p) and e in far), default=math.nan
    )
    shortest = {}
    for e, p in eyes.items():
        shortest[e] = (
            _towards(p, eyes, to_source.get(e), arena.source),
            _towards(p, eyes, to_target.get(e), arena.target),
        )
    return replace(arena, shortest=shortest, optimum=optimum)


def _towards(
    at: tuple[float, float],
    eyes: dict[str, tuple[float, float]],
    nxt: str | None,
    goal: tuple[float, float],
) -> float:
    to = eyes[nxt] if nxt is not None else goal
    return math.atan2(to[1] - at[1], to[0] - at[0])


def _dijkstra(
    edges: dict[str, list[tuple[str, float]]], goals: list[str]
) -> tuple[dict[str, str], dict[str, float]]:
    """For each eye-bot, the next eye-bot on a shortest path to one of ``goals`` (goals
    themselves have none), and each one's distance to the nearest goal."""
    dist = {g: 0.0 for g in goals}
    nxt: dict[str, str] = {}
    heap = [(0.0, g) for g in goals]
    while heap:
        d, a = heapq.heappop(heap)
        if d > dist.get(a, math.inf):
            continue
        for b, w in edges[a]:
            if d + w < dist.get(b, math.inf):
                dist[b] = d + w
                nxt[b] = a
                heapq.heappush(heap, (d + w, b))
    return nxt, dist


def _clear(
    obstacles: tuple[ObstacleSpec, ...], a: tuple[float, float], b: tuple[float, float]
) -> bool:
    """Whether a foot-bot can drive straight from a to b: no circle or box (axis-aligned, as in
    these arenas) within CLEARANCE of the segment, checked every 5 cm."""
    steps = max(1, math.ceil(math.dist(a, b) / 0.05))
    for k in range(steps + 1):
        x = a[0] + (b[0] - a[0]) * k / steps
        y = a[1] + (b[1] - a[1]) * k / steps
        for ob in obstacles:
            if ob.shape == "circle":
                if math.hypot(x - ob.center[0], y - ob.center[1]) <= ob.radius + CLEARANCE:
                    return False
                continue
            hx, hy = ob.size[0] / 2 + CLEARANCE, ob.size[1] / 2 + CLEARANCE
            if abs(x - ob.center[0]) <= hx and abs(y - ob.center[1]) <= hy:
                return False
    return True
