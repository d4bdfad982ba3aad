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


def test_a_maze_table_says_sd_and_keeps_one_precision() -> None:
    """Rounds of 150 and 80 beside 1.5 in one table: one precision for all (before, 150 read
    "150" and 1.5 read "1.50" in the same table)."""
    from experiments.maze._paper import EXTRA, METRICS
    from experiments.maze._report import tables

    keys = [k for k, *_ in METRICS] + [k for k, _ in EXTRA]
    records = [
        {"p": 0.85, "method": m, "agents": n, "complete": True, **dict.fromkeys(keys, v)}
        for m, n, v in (("a", 4, 150.0), ("a", 8, 80.0), ("b", 4, 1.5), ("b", 8, 1.5))
    ]
    text = tables(records, ["a", "b"], [4, 8])
    rounds = text.split("exploration rounds")[1].split("\n\n")[0]
    assert "(mean ± sd over the runs)" in rounds
    assert "150 ± 0" in rounds and "2 ± 0" in rounds and "1.50" not in rounds
