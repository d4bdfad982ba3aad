"""Every robot's sonar in one batch: numpy over a spatial hash for the robots' discs near each
sonar, chipmunk for the rays that hit none of them and for the rays that may reach anything else.

The readings are those of one ``cpSpaceSegmentQueryFirst`` per ray (``_devices.sonar_ranges``,
kept as the reference), bit for bit: a ray's range is its first hit's ``alpha`` times the
range, and the first hit is the least ``alpha`` over the shapes it meets, so the least over the
robots' discs within NEAR (computed here with chipmunk's own circle query, operation for
operation) and over the other solid shapes (asked of chipmunk, for the rays whose box touches
one) is the same number when a disc that near was hit; a ray that hit none (an open ray) is
asked of chipmunk whole, as the reference asks it. Noise is drawn from each robot's generator
in ray order, as the reference does.

Why: one chipmunk query costs ~1.5-2.5 µs through cffi, 8 rays a robot 12-20 ms a tick at 1000
robots; here most rays of a crowd end at a disc within NEAR, found by a few numpy passes over
the rays and the robot pairs that near (docs/physics.md gives the figures).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pymunk
from pymunk._chipmunk import ffi as _ffi
from pymunk._chipmunk import lib as _lib

from ._bodies import CAT_QUERY, CAT_ROBOT, SOLID

_INFO = _ffi.new("cpSegmentQueryInfo *")
_OTHERS = SOLID & ~CAT_ROBOT
_SLACK = 1e-6
"""Metres added to every pruning bound (the exact test decides; this only keeps candidates)."""
_ANGLE_SLACK = 1e-6
"""Radians added to a disc's angular width when choosing the rays to try on it."""
NEAR = 1.0
"""Metres: the discs this near a sonar are tried first (in a crowd most rays end there)."""
PAIRS_PER_QUERY = 8.0
"""What a chipmunk query of a ray costs, in candidate (sonar, disc) pairs of numpy's far pass
(``bench/sim.py``'s 200 and 1000 robots, crowded and spread: a query 1.6-2.5 µs, a candidate
0.13-0.31 µs; see :func:`_queries_cheaper`)."""


def _trig_is_libm() -> bool:
    """Whether numpy's cos and sin give what ``math`` gives on this machine (the reference
    uses ``math``): checked once on a fixed sample."""
    x = np.random.default_rng(7).uniform(-8.0, 8.0, 4096)
    xs = x.tolist()
    return bool(
        np.array_equal(np.cos(x), np.fromiter(map(math.cos, xs), float, len(xs)))
        and np.array_equal(np.sin(x), np.fromiter(map(math.sin, xs), float, len(xs)))
    )


_NUMPY_TRIG = _trig_is_libm()


def cos_sin(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``math.cos`` and ``math.sin`` of every element (numpy's where they agree, else math's)."""
    if _NUMPY_TRIG:
        return np.cos(theta), np.sin(theta)
    xs = theta.tolist()
    n = len(xs)
    return np.fromiter(map(math.cos, xs), float, n), np.fromiter(map(math.sin, xs), float, n)


@dataclass(slots=True)
class Sonar:
    """One robot's sonar as the batch reads it: where the robot is (``index`` into the
    discs), its rim, ray angles, range, noise and generator."""

    index: int
    group: int
    angles: tuple[float, ...]
    max_range: float
    noise: float
    rng: np.random.Generator
    angle_array: np.ndarray = field(init=False)
    spread: float = field(init=False)
    """The angle between rays if they are spread evenly from 0 (as SonarSpec makes them),
    else 0."""

    def __post_init__(self) -> None:
        self.angle_array = np.array(self.angles, dtype=float)
        n = len(self.angles)
        even = n > 0 and self.angles == tuple(2.0 * math.pi * i / n for i in range(n))
        self.spread = 2.0 * math.pi / n if even else 0.0


@dataclass(slots=True)
class _Rays:
    """Every ray of a batch: its disc, direction, start (rim), end, and range."""

    owner: np.ndarray
    c: np.ndarray
    s: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    bx: np.ndarray
    by: np.ndarray
    far: np.ndarray
    reach: np.ndarray


@dataclass(slots=True)
class _Sonars:
    """The batch's sonars as arrays: each one's disc, ray count, first ray, angle between its
    rays (see :class:`Sonar`) and farthest reach from its disc's centre."""

    index: np.ndarray
    counts: np.ndarray
    first_ray: np.ndarray
    spread: np.ndarray
    far: np.ndarray


@dataclass(slots=True)
class Discs:
    """Every robot's disc now: centre, heading, radius and shape filter group."""

    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    radius: np.ndarray
    group: np.ndarray


def sonar_batch(
    space: pymunk.Space, discs: Discs, sonars: Sequence[Sonar], others: Sequence[pymunk.Shape]
) -> list[list[float]]:
    """The ranges of each of ``sonars`` (as ``_devices.sonar_ranges`` gives them). ``others``
    are the solid shapes in ``space`` that are not robots' discs."""
    if not sonars:
        return []
    counts = np.fromiter((len(so.angles) for so in sonars), np.intp, len(sonars))
    first_ray = np.cumsum(counts) - counts
    owner_s = np.repeat(np.arange(len(sonars)), counts)  # ray -> sonar
    index = np.fromiter((so.index for so in sonars), np.intp, len(sonars))
    owner = index[owner_s]  # ray -> disc
    angles = np.concatenate([so.angle_array for so in sonars])
    reach_s = np.fromiter((so.max_range for so in sonars), float, len(sonars))
    c, s = cos_sin(discs.heading[owner] + angles)
    rim = discs.radius[owner]
    far = rim + reach_s[owner_s]
    x0, y0 = discs.x[owner], discs.y[owner]
    ax, ay = x0 + c * rim, y0 + s * rim
    bx, by = x0 + c * far, y0 + s * far
    reach = reach_s[owner_s]
    alpha = np.ones(len(owner))
    spread = np.fromiter((so.spread for so in sonars), float, len(sonars))
    rays = _Rays(owner, c, s, ax, ay, bx, by, far, reach)
    batch = _Sonars(index, counts, first_ray, spread, np.maximum.reduceat(far, first_ray))
    open_ = _discs_near(alpha, discs, batch, rays)
    rest = np.ones(len(alpha), bool)  # the rays that may still meet a shape nearer
    if _queries_cheaper(discs, batch, reach_s, open_):
        _whole(alpha, space, sonars, owner_s, rays, open_)
        rest = ~open_
    elif open_.any():
        _discs_far(alpha, discs, batch, rays, open_)
    _others_first(alpha, space, others, sonars, owner_s, rays, rest)
    hits = alpha < 1.0
    ranges = np.where(hits, alpha * reach, reach)  # no hit: the range itself
    noisy_ones = np.fromiter((so.noise > 0.0 for so in sonars), bool, len(sonars))
    for k in np.flatnonzero(noisy_ones).tolist():
        sonar = sonars[k]
        mine = slice(int(first_ray[k]), int(first_ray[k] + counts[k]))
        hit = np.flatnonzero(hits[mine]) + mine.start
        if len(hit):  # drawn in ray order from the robot's generator, as the reference does
            noisy = ranges[hit] + sonar.rng.normal(0.0, sonar.noise, len(hit))
            ranges[hit] = np.minimum(np.maximum(noisy, 0.0), sonar.max_range)
    flat = ranges.tolist()
    ends = (first_ray + counts).tolist()
    return [flat[a:b] for a, b in zip(first_ray.tolist(), ends, strict=True)]


def _pairs(discs: Discs, index: np.ndarray, bound: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (k, j): disc j (not sonar k's own, nor of its group) within ``bound[k]`` plus its
    radius of sonar k's centre; a grid of cells as wide as the largest such distance."""
    cell = float(bound.max() + discs.radius.max()) + _SLACK
    cx = np.floor(discs.x / cell).astype(np.int64)
    cy = np.floor(discs.y / cell).astype(np.int64)
    span = int(cy.max() - cy.min()) + 3
    key = (cx - cx.min() + 1) * span + (cy - cy.min() + 1)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    ks, js = [], []
    mine = key[index]
    for dx in (-1, 0, 1):  # a column of three cells is one run of keys
        lo = np.searchsorted(sorted_key, mine + dx * span - 1, "left")
        hi = np.searchsorted(sorted_key, mine + dx * span + 1, "right")
        size = hi - lo
        total = int(size.sum())
        if not total:
            continue
        ks.append(np.repeat(np.arange(len(index)), size))
        first = np.repeat(np.cumsum(size) - size, size)
        js.append(order[np.repeat(lo, size) + np.arange(total) - first])
    if not ks:
        return np.empty(0, np.intp), np.empty(0, np.intp)
    k, j = np.concatenate(ks), np.concatenate(js)
    i = index[k]
    dx, dy = discs.x[j] - discs.x[i], discs.y[j] - discs.y[i]
    near = bound[k] + discs.radius[j] + _SLACK
    keep = (dx * dx + dy * dy <= near * near) & (discs.group[j] != discs.group[i])
    return k[keep], j[keep]


def _discs_near(alpha: np.ndarray, discs: Discs, batch: _Sonars, rays: _Rays) -> np.ndarray:
    """Lower ``alpha`` to each ray's first hit on a robot's disc within NEAR of its sonar
    (chipmunk's circle query); return the rays still open: those whose sonar reaches past NEAR
    and that hit no disc that near (a disc farther than NEAR cannot be hit nearer than NEAR
    along a ray from the centre)."""
    near = np.minimum(batch.far, NEAR)
    _pass(alpha, discs, batch.index, batch.counts, batch.spread, batch.first_ray, near, rays)
    reached = discs.radius[rays.owner] + alpha * rays.reach  # hit distance from the centre
    open_: np.ndarray = ~((alpha < 1.0) & (reached <= NEAR - _SLACK))
    open_ &= np.repeat(batch.far > NEAR, batch.counts)
    return open_


def _queries_cheaper(discs: Discs, batch: _Sonars, reach: np.ndarray, open_: np.ndarray) -> bool:
    """Whether asking chipmunk for each open ray (:func:`_whole`) should cost less than numpy
    over the discs on the grid cells around their sonars (:func:`_discs_far`): in a crowd few
    rays stay open and each sonar has many discs near, spread out most rays stay open past
    few. The candidates (a sonar's 3 x 3 cells as wide as its reach) are estimated from the
    discs' density over the box they fill; a query costs about as much as PAIRS_PER_QUERY
    candidates (either way the readings are the same)."""
    rays = int(open_.sum())
    if not rays:
        return False
    sonars = int(np.count_nonzero(np.add.reduceat(open_, batch.first_ray)))
    far = float(reach.max() + discs.radius.max())
    area = (float(np.ptp(discs.x)) + 2 * far) * (float(np.ptp(discs.y)) + 2 * far)
    candidates = sonars * len(discs.x) * 9 * far * far / area
    return candidates > PAIRS_PER_QUERY * rays


def _discs_far(
    alpha: np.ndarray, discs: Discs, batch: _Sonars, rays: _Rays, open_: np.ndarray
) -> None:
    """Lower ``alpha`` of the ``open_`` rays to their first hit on any disc within their
    sonar's reach."""
    sub = np.flatnonzero(np.add.reduceat(open_, batch.first_ray) > 0)
    _pass(
        alpha,
        discs,
        batch.index[sub],
        batch.counts[sub],
        batch.spread[sub],
        batch.first_ray[sub],
        batch.far[sub],
        rays,
        open_,
    )


def _whole(
    alpha: np.ndarray,
    space: pymunk.Space,
    sonars: Sequence[Sonar],
    owner_s: np.ndarray,
    rays: _Rays,
    only: np.ndarray,
) -> None:
    """Set ``alpha`` of the rays ``only`` to their first hit on any solid shape, asked of
    chipmunk as the reference asks it (in a crowd a quarter to a half of the rays; numpy over
    every disc within their reach cost more than these queries from ~200 robots on)."""
    cspace, info, null = space._space, _INFO, _ffi.NULL
    query = _lib.cpSpaceSegmentQueryFirst
    rows = np.flatnonzero(only)
    starts = zip(rays.ax[rows].tolist(), rays.ay[rows].tolist(), strict=True)
    ends = zip(rays.bx[rows].tolist(), rays.by[rows].tolist(), strict=True)
    out = []
    last, owner, shape_filter = -1, None, None
    for k, start, end in zip(owner_s[rows].tolist(), starts, ends, strict=True):
        if k != last:  # a sonar's rays are in a row: one filter struct for them
            last = k
            owner = _ffi.new("cpShapeFilter *", (sonars[k].group, CAT_QUERY, SOLID))
            shape_filter = owner[0]  # (valid while ``owner`` lives)
        hit = query(cspace, start, end, 0.0, shape_filter, info) != null
        out.append(info.alpha if hit else 1.0)
    alpha[rows] = out


def _pass(
    alpha: np.ndarray,
    discs: Discs,
    index: np.ndarray,
    counts: np.ndarray,
    spread: np.ndarray,
    first_ray: np.ndarray,
    bound: np.ndarray,
    rays: _Rays,
    only: np.ndarray | None = None,
) -> None:
    """Lower ``alpha`` of the rays of sonars ``index`` (``only`` those, if given) to their
    first hit on the discs within ``bound`` of each."""
    k, j = _pairs(discs, index, bound)
    if not len(k):
        return
    # the rays of sonar k that may meet disc j: those within its angular width (rays spread
    # evenly, as SonarSpec makes them), else every ray of the sonar
    i = index[k]
    dx, dy = discs.x[j] - discs.x[i], discs.y[j] - discs.y[i]
    d = np.sqrt(dx * dx + dy * dy)
    n = counts[k]
    step = spread[k]
    with np.errstate(invalid="ignore", divide="ignore"):
        width = np.arcsin(np.minimum((discs.radius[j] + _SLACK) / d, 1.0)) + _ANGLE_SLACK
        bearing = np.arctan2(dy, dx) - discs.heading[i]
        lo = np.ceil((bearing - width) / step)
        hi = np.floor((bearing + width) / step)
    every = (step == 0.0) | (d <= discs.radius[j] + _SLACK) | ~np.isfinite(lo + hi)
    lo = np.where(every, 0, lo).astype(np.intp)
    per = np.where(every, n, np.clip(hi.astype(np.intp, copy=False) - lo + 1, 0, n))
    total = int(per.sum())
    if not total:
        return
    nth = np.arange(total) - np.repeat(np.cumsum(per) - per, per)
    ray = np.repeat(first_ray[k], per) + (np.repeat(lo, per) + nth) % np.repeat(n, per)
    j = np.repeat(j, per)
    if only is not None:
        keep = only[ray]
        ray, j = ray[keep], j[keep]
    cx, cy, r = discs.x[j], discs.y[j], discs.radius[j]
    owner = rays.owner[ray]
    dx, dy = cx - discs.x[owner], cy - discs.y[owner]
    c, s = rays.c[ray], rays.s[ray]
    along = dx * c + dy * s
    side = dx * s - dy * c
    keep = (np.abs(side) <= r + _SLACK) & (along >= -r - _SLACK)
    keep &= along <= rays.far[ray] + r + _SLACK
    ray, cx, cy, r = ray[keep], cx[keep], cy[keep], r[keep]
    if not len(ray):
        return
    # cpShapeSegmentQuery: a start inside the disc is a hit at 0 (cpCircleShapePointQuery)
    dax, day = rays.ax[ray] - cx, rays.ay[ray] - cy
    dbx, dby = rays.bx[ray] - cx, rays.by[ray] - cy
    dd = dax * dax + day * day
    inside = np.sqrt(dd) - r <= 0.0
    # CircleSegmentQuery (chipmunk_private.h), r2 = 0
    db = dax * dbx + day * dby
    qa = dd - 2.0 * db + (dbx * dbx + dby * dby)
    qb = db - dd
    rsum = r + 0.0
    det = qb * qb - qa * (dd - rsum * rsum)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (-qb - np.sqrt(np.where(det >= 0.0, det, 0.0))) / qa
    t = np.where(inside, 0.0, t)
    hit = inside | ((det >= 0.0) & (t >= 0.0) & (t <= 1.0))
    np.minimum.at(alpha, ray[hit], t[hit])


def _others_first(
    alpha: np.ndarray,
    space: pymunk.Space,
    others: Sequence[pymunk.Shape],
    sonars: Sequence[Sonar],
    owner_s: np.ndarray,
    rays: _Rays,
    only: np.ndarray,
) -> None:
    """Lower ``alpha`` of the rays ``only`` to their first hit on any other solid shape, asked
    of chipmunk for the rays whose bounding box touches one's."""
    if not others:
        return
    ax, ay, bx, by = rays.ax, rays.ay, rays.bx, rays.by
    # a shape hit nearer than the disc hit (if any) touches the box of the ray up to it
    ex, ey = ax + (bx - ax) * alpha, ay + (by - ay) * alpha
    lox, hix = np.minimum(ax, ex) - _SLACK, np.maximum(ax, ex) + _SLACK
    loy, hiy = np.minimum(ay, ey) - _SLACK, np.maximum(ay, ey) + _SLACK
    near = np.zeros(len(ax), bool)
    for shape in others:
        bb = shape.bb
        near |= (lox <= bb.right) & (hix >= bb.left) & (loy <= bb.top) & (hiy >= bb.bottom)
    cspace, info, null = space._space, _INFO, _ffi.NULL
    query = _lib.cpSpaceSegmentQueryFirst
    for i in np.flatnonzero(near & only).tolist():
        group = sonars[int(owner_s[i])].group
        start, end = (float(ax[i]), float(ay[i])), (float(bx[i]), float(by[i]))
        hit = query(cspace, start, end, 0.0, (group, CAT_QUERY, _OTHERS), info) != null
        if hit and info.alpha < alpha[i]:
            alpha[i] = info.alpha
