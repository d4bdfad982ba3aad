"""Stigmergic navigation in-process: the arenas, and seeded runs of the eye-bots and foot-bots."""

import math

import pytest

from experiments.eyebot._arena import SPACING, cluttered, corridors
from experiments.eyebot._trial import Settings, run


def test_the_cluttered_arena_has_a_way_through_its_eye_bots() -> None:
    arena = cluttered()
    assert len(arena.eyebots) == 24
    old = {e.id: e.center for e in cluttered(over_walls=True).eyebots}
    assert len(old) == 28
    # the four left out are exactly the ones over a wall (x = 4 and x = 8)
    assert sorted(set(old) - {e.id for e in arena.eyebots}) == ["e101", "e103", "e301", "e303"]
    assert all(old[e][0] in (4.0, 8.0) for e in ("e101", "e103", "e301", "e303"))
    ids = {e.id: e.center for e in arena.eyebots}
    # every lattice neighbour lies in one of the 12 directions
    for a in ids.values():
        for b in ids.values():
            if a != b and math.dist(a, b) < SPACING + 1e-6:
                angle = math.degrees(math.atan2(b[1] - a[1], b[0] - a[0]))
                assert round(angle) % 30 == 0
    assert arena.in_target(*arena.target) and arena.in_source(*arena.source)
    assert not arena.in_source(*arena.target)


@pytest.mark.parametrize("ratio", [1.0, 2.0])
def test_the_double_corridor_has_eye_bots_along_both_corridors(ratio: float) -> None:
    arena = corridors(ratio)
    assert arena.corridors is not None
    divide, y0, y1 = arena.corridors
    inside = [e.center for e in arena.eyebots if y0 < e.center[1] < y1]
    right = [c for c in inside if c[0] > divide]
    left = [c for c in inside if c[0] < divide]
    assert len(right) == 10
    assert len(left) == pytest.approx(10 * ratio, abs=1)


def test_eye_bots_showing_the_shortest_way_guide_a_foot_bot_near_the_optimum() -> None:
    figures = run(cluttered(), Settings(footbots=1, duration=200.0, shortest=True), seed=3)
    # the way through the eye-bots is 16 m: 53 s at 0.3 m/s, plus the ends in the areas
    assert figures["t_1"] is not None and 45.0 < figures["t_1"] < 90.0
    assert figures["trips"] >= 2
    assert figures["t_a"] is not None and figures["t_a"] < 90.0


def test_a_run_is_the_same_for_the_same_seed() -> None:
    settings = Settings(footbots=3, duration=60.0)
    a, b = run(cluttered(), settings, seed=5), run(cluttered(), settings, seed=5)
    for key in ("t_1", "t_a", "trips"):
        assert a[key] == b[key]
    c = run(corridors(1.0), Settings(footbots=2, duration=60.0, window=30.0), seed=5)
    assert c["c_r"] + c["c_l"] > 0  # foot-bots were counted in the corridors


def test_the_mirrored_double_corridor_is_the_plain_one_left_to_right() -> None:
    plain, mirrored = corridors(2.0), corridors(2.0, mirrored=True)
    w = plain.spec.size[0]
    assert mirrored.mirrored and not plain.mirrored
    flipped = {e.id: (round(w - e.center[0], 9), round(e.center[1], 9)) for e in plain.eyebots}
    assert flipped == {
        e.id: (round(e.center[0], 9), round(e.center[1], 9)) for e in mirrored.eyebots
    }
    assert mirrored.source == pytest.approx((w - plain.source[0], plain.source[1]))
    assert mirrored.optimum == pytest.approx(plain.optimum)
    # each eye-bot's shortest-way directions are mirrored too: θ → π − θ
    for e in plain.eyebots:
        for a, b in zip(plain.shortest[e.id], mirrored.shortest[e.id], strict=True):
            assert math.cos(b) == pytest.approx(-math.cos(a), abs=1e-9)
            assert math.sin(b) == pytest.approx(math.sin(a), abs=1e-9)


@pytest.mark.parametrize("mirrored", [False, True])
def test_rho_is_the_shorter_corridors_share_mirrored_or_not(mirrored: bool) -> None:
    # eye-bots showing the shortest way send the foot-bots along the shorter corridor: on the
    # right in the plain arena, on the left in the mirrored one; ρ counts it either way
    arena = corridors(2.0, mirrored=mirrored)
    figures = run(arena, Settings(footbots=2, duration=150.0, window=100.0, shortest=True), 4)
    assert figures["c_r"] > 0 and figures["rho"] is not None and figures["rho"] > 0.9
