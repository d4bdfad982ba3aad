"""The paper's figures from foot-bots' trips: t_1, t_a over all later trips and over those begun
in the run's second half."""

from typing import Any

import pytest

from robots.stigmergic import travel_times

TRIPS: dict[str, list[list[Any]]] = {
    # goal, start, end: the first trip of each is exploration and is not in t_a
    "f0": [["target", 0.0, 500.0], ["source", 500.0, 1400.0], ["target", 1600.0, 1700.0]],
    "f1": [["target", 0.0, 300.0], ["source", 300.0, 400.0], ["target", 1500.0, 1800.0]],
}


def test_t_a_counts_the_later_trips_over_the_run_and_over_its_second_half() -> None:
    got = travel_times(TRIPS, 0.0, duration=3000.0)
    assert got["t_1"] == 300.0
    assert got["later"] == 4 and got["t_a"] == pytest.approx((900 + 100 + 100 + 300) / 4)
    assert got["t_a_median"] == pytest.approx(200.0)
    # begun at 1500 s or later: the trips from 1600 and from 1500 (not the one from 500)
    assert got["late"] == 2 and got["t_a_late"] == pytest.approx((100 + 300) / 2)


def test_the_second_half_is_taken_from_the_start_and_none_is_none() -> None:
    shifted = {r: [[g, s + 100.0, e + 100.0] for g, s, e in t] for r, t in TRIPS.items()}
    assert travel_times(shifted, 100.0, 3000.0)["t_a_late"] == pytest.approx(200.0)
    early = travel_times(TRIPS, 0.0, duration=4000.0)  # second half from 2000 s: none begun
    assert early["late"] == 0 and early["t_a_late"] is None
    assert "t_a_late" not in travel_times(TRIPS, 0.0)  # no duration given, no second half
