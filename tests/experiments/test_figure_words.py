"""Captions count runs in good English, and a table column keeps one precision."""

from __future__ import annotations

from experiments._figures import runs_label, shared_precision


def test_one_run_is_singular() -> None:
    assert [runs_label(n) for n in (0, 1, 2, 50)] == ["0 runs", "1 run", "2 runs", "50 runs"]


def test_a_column_takes_the_precision_of_its_largest_mean() -> None:
    assert shared_precision([0.5, 3.25, 140.0]) == 0
    assert shared_precision([0.5, 3.25]) == 2
    assert shared_precision([0.5, -0.01]) == 4
    assert shared_precision([]) == 4
