"""Unit tests of the range filter, noise model and neighbour table (no network)."""

from __future__ import annotations

import math

import pytest

from mover import FixedLocator, RadioModel
from mover._radio import Radio


def test_range_distance_and_bearing_in_the_receivers_frame() -> None:
    radio = Radio(FixedLocator(1.0, 1.0, math.pi / 2), None)
    m = radio.receive("s", "t", 1, [1.0, 3.0], 2.5, 0.0)
    assert m is not None
    assert m.distance == pytest.approx(2.0)
    assert m.bearing == pytest.approx(0.0)  # straight ahead
    m = radio.receive("s", "t", 1, [0.0, 1.0], 2.5, 0.0)
    assert m is not None and m.bearing == pytest.approx(math.pi / 2)  # to the left
    assert radio.receive("s", "t", 1, [4.0, 1.0], 2.5, 0.0) is None
    assert radio.out_of_range == 1


def test_unknown_positions_cannot_be_in_range_but_team_wide_passes() -> None:
    assert Radio(None, None).receive("s", "t", 1, [0, 0], 10.0, 0.0) is None
    m = Radio(None, None).receive("s", "t", 1, None, None, 0.0)
    assert m is not None and m.distance is None


def test_drop_and_noise_are_seeded() -> None:
    def run(seed: int) -> list[float | None]:
        radio = Radio(FixedLocator(0, 0), RadioModel(drop=0.3, range_noise=0.1, seed=seed))
        out = []
        for _ in range(200):
            m = radio.receive("s", "t", 1, [3.0, 4.0], 10.0, 0.0)
            out.append(None if m is None else m.distance)
        return out

    a, b = run(1), run(1)
    assert a == b
    lost = sum(x is None for x in a)
    assert 30 < lost < 90
    kept = [x for x in a if x is not None]
    assert abs(sum(kept) / len(kept) - 5.0) < 0.05 and len(set(kept)) > 10


def test_neighbour_table() -> None:
    radio = Radio(FixedLocator(0, 0), None)
    radio.receive("a", "t", 1, [3.0, 4.0], None, 0.0)
    assert radio.neighbours()["a"].distance == pytest.approx(5.0)
    radio.forget("a")
    assert radio.neighbours() == {}
