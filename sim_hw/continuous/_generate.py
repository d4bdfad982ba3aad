"""Seeded generators of continuous arenas: random obstacle fields, free points in them (where
targets and robots go), and double corridors."""

from __future__ import annotations

import math

import numpy as np

from ._spec import MarkerSpec, ObstacleSpec, WorldSpec


def random_obstacles(
    size: tuple[float, float] = (10.0, 10.0),
    count: int = 20,
    rng: np.random.Generator | None = None,
    *,
    min_size: float = 0.2,
    max_size: float = 0.8,
    clearance: float = 0.6,
    keep_clear: tuple[tuple[float, float, float], ...] = (),
) -> WorldSpec:
    """An arena with up to ``count`` boxes and discs placed at random, ``clearance`` apart from
    each other and from the walls, and away from each ``(x, y, radius)`` in ``keep_clear`` (the
    bottom-left spawn corner is always kept clear). Same generator state → same arena."""
    rng = rng if rng is not None else np.random.default_rng(0)
    w, h = size
    placed: list[tuple[float, float, float]] = [(0.0, 0.0, 2.0), *keep_clear]
    obstacles: list[ObstacleSpec] = []
    for _ in range(count * 50):
        if len(obstacles) >= count:
            break
        extent = float(rng.uniform(min_size, max_size))
        r = extent / 2 * (math.sqrt(2) if extent else 1)
        x = float(rng.uniform(r + clearance, max(r + clearance, w - r - clearance)))
        y = float(rng.uniform(r + clearance, max(r + clearance, h - r - clearance)))
        round_one = bool(rng.integers(2))
        angle = float(rng.uniform(0, math.pi))
        if any(math.hypot(x - px, y - py) < r + pr + clearance for px, py, pr in placed):
            continue
        placed.append((x, y, r))
        if round_one:
            obstacles.append(ObstacleSpec("circle", center=(x, y), radius=extent / 2))
        else:
            obstacles.append(ObstacleSpec("box", center=(x, y), size=(extent, extent), angle=angle))
    return WorldSpec(size=size, name=f"random-{count}", obstacles=tuple(obstacles))


def free_points(
    spec: WorldSpec,
    count: int,
    rng: np.random.Generator,
    *,
    clearance: float = 0.5,
    apart: float = 0.0,
    avoid: tuple[tuple[float, float], ...] = (),
) -> list[tuple[float, float]]:
    """``count`` points drawn uniformly in ``spec``'s arena, each ``clearance`` from the walls
    and from every obstacle's bounding circle, and ``apart`` from each other and from the
    points in ``avoid``. Same generator state → same points. Raises ``ValueError`` when the
    arena is too full to place them (after 1000 draws a point)."""
    w, h = spec.size
    discs = [_bounding_circle(ob) for ob in spec.obstacles]
    placed: list[tuple[float, float]] = []
    others = list(avoid)
    for _ in range(count * 1000):
        if len(placed) >= count:
            return placed
        x = float(rng.uniform(clearance, w - clearance))
        y = float(rng.uniform(clearance, h - clearance))
        if any(math.hypot(x - cx, y - cy) < r + clearance for cx, cy, r in discs):
            continue
        if any(math.hypot(x - px, y - py) < apart for px, py in others):
            continue
        placed.append((x, y))
        others.append((x, y))
    if len(placed) < count:
        raise ValueError(f"could place only {len(placed)} of {count} points")
    return placed


def _bounding_circle(ob: ObstacleSpec) -> tuple[float, float, float]:
    if ob.shape == "circle":
        return (ob.center[0], ob.center[1], ob.radius)
    if ob.shape == "box":
        return (ob.center[0], ob.center[1], math.hypot(*ob.size) / 2)
    cx, cy = (ob.a[0] + ob.b[0]) / 2, (ob.a[1] + ob.b[1]) / 2
    half = math.hypot(ob.b[0] - ob.a[0], ob.b[1] - ob.a[1]) / 2
    return (cx, cy, half + ob.radius)


def double_corridor(
    length: float = 20.0, ratio: float = 1.0, width: float = 1.0, room: float = 3.0
) -> WorldSpec:
    """Ducatelle et al.'s double corridor (Fig. 3): a source room (bottom) and a target room
    (top), each ``room`` deep, joined by a straight right corridor of ``length`` and a left one
    ``ratio`` times as long: it leaves the rooms as far to the left of the source and target as
    the right one does to their right, and makes a sideways detour of ``(ratio - 1) · length / 2``
    walled off from the rooms. Markers ``source`` and ``target`` sit in the middle of the rooms;
    :func:`corridor_paths` gives the corridors' middle lines."""
    size, free, paths = _double_corridor(length, ratio, width, room)
    w, h = size
    middle = paths["right"][0][0] - 1.5 * width  # the source and target are between the two
    y0, y1 = room, h - room
    xs = sorted({0.0, w, *(v for r in free for v in (r[0], r[2]))})
    ys = sorted({y0, y1, *(v for r in free for v in (r[1], r[3]))})
    obstacles = []
    for i in range(len(xs) - 1):
        for j in range(len(ys) - 1):
            cx, cy = (xs[i] + xs[i + 1]) / 2, (ys[j] + ys[j + 1]) / 2
            sx, sy = xs[i + 1] - xs[i], ys[j + 1] - ys[j]
            if sx <= 1e-9 or sy <= 1e-9:
                continue
            if any(a <= cx <= c2 and b <= cy <= d for a, b, c2, d in free):
                continue
            obstacles.append(ObstacleSpec("box", center=(cx, cy), size=(sx, sy)))
    markers = (
        MarkerSpec("target", "source", (middle, room / 2), 0.5),
        MarkerSpec("target", "target", (middle, y1 + room / 2), 0.5),
    )
    return WorldSpec(
        size=size,
        name=f"double-corridor-r{ratio:g}",
        obstacles=tuple(obstacles),
        markers=markers,
    )


def corridor_paths(
    length: float = 20.0, ratio: float = 1.0, width: float = 1.0, room: float = 3.0
) -> dict[str, tuple[tuple[float, float], ...]]:
    """The middle lines of :func:`double_corridor`'s corridors, from the source room to the
    target room: ``{"right": ..., "left": ...}``, each a polyline."""
    return _double_corridor(length, ratio, width, room)[2]


Rect = tuple[float, float, float, float]


def _double_corridor(
    length: float, ratio: float, width: float, room: float
) -> tuple[tuple[float, float], list[Rect], dict[str, tuple[tuple[float, float], ...]]]:
    """The arena's size, its free rectangles in the corridor band, and the middle lines."""
    if ratio < 1.0:
        raise ValueError("ratio must be >= 1")
    c, margin = width, 1.0
    stub = 2.0 * c  # the left corridor goes this far up (down) before it turns sideways
    if ratio > 1.0 and length < 2 * stub + c:
        raise ValueError(f"length must be at least {2 * stub + c:g} for a detour")
    detour = (ratio - 1.0) * length / 2.0
    middle = margin + c / 2 + detour + 1.5 * c  # x of the source and target
    xl, xr = middle - 1.5 * c, middle + 1.5 * c
    w = xr + c / 2 + margin
    y0, y1 = room, room + length
    h = y1 + room
    half = c / 2
    free: list[Rect] = [(xr - half, y0, xr + half, y1)]
    right = ((xr, y0), (xr, y1))
    if detour == 0.0:
        free.append((xl - half, y0, xl + half, y1))
        left: tuple[tuple[float, float], ...] = ((xl, y0), (xl, y1))
    else:
        xd, ya, yb = xl - detour, y0 + stub, y1 - stub
        free += [
            (xl - half, y0, xl + half, ya + half),
            (xd - half, ya - half, xl + half, ya + half),
            (xd - half, ya - half, xd + half, yb + half),
            (xd - half, yb - half, xl + half, yb + half),
            (xl - half, yb - half, xl + half, y1),
        ]
        left = ((xl, y0), (xl, ya), (xd, ya), (xd, yb), (xl, yb), (xl, y1))
    return (w, h), free, {"right": right, "left": left}
