"""The eye-bot runner's Fig. 2 table with every run counted: a run without t_a is not dropped."""

from experiments.eyebot._report import fig2_counted


def _learn(t_1: float | None, t_a: float | None, late: float | None) -> dict[str, object]:
    return {
        "arena": "eyebot-cluttered",
        "footbots": 10,
        "eyebots": "learning",
        "duration": 3000.0,
        "t_1": t_1,
        "t_a": t_a,
        "t_a_late": late,
        "t_a_median": t_a,
    }


def test_a_run_without_a_trip_counts_as_the_span_it_had() -> None:
    records = [
        _learn(200.0, 100.0, 90.0),
        _learn(None, None, None),  # never arrived: t_1 and t_a 3000, late 1500
        {"arena": "eyebot-cluttered", "footbots": 10, "eyebots": "shortest", "t_a_all": 100.0},
    ]
    row = next(line for line in fig2_counted(records).splitlines() if line.split()[:1] == ["10"])
    cells = row.split()
    # foot-bots, runs, t_1, t_a, none, late, none, median, t_s, ratios, checks
    assert cells[:9] == ["10", "2", "1600", "1550", "1", "795", "1", "1550", "100"]
    assert cells[9:12] == ["15.50", "7.95", "15.50"]
    assert cells[12:] == ["no", "no", "yes"]


def test_without_t_s_runs_the_bounds_are_not_decided() -> None:
    table = fig2_counted([_learn(200.0, 100.0, 90.0)])
    row = next(line for line in table.splitlines() if line.split()[:1] == ["10"])
    assert row.split()[-3:] == ["-", "-", "yes"]


def test_fig3_says_the_window_its_runs_used() -> None:
    """A 300 s run's ρ is over its last 300 s, not "the last 1000 s" (runs saved before the
    window was kept read 1000 s, as they were made)."""
    from experiments.eyebot._report import fig3
    from experiments.eyebot._sweep import FIG3_FOOTBOTS

    def run(window: float | None) -> dict[str, object]:
        record: dict[str, object] = {"arena": "double-corridor-r2", "footbots": FIG3_FOOTBOTS}
        record |= {"eyebots": "learning", "rho": 0.9}
        return record if window is None else {**record, "window": window}

    assert "over the last 300 s" in fig3([run(300.0)])
    assert "over the last 1000 s" in fig3([run(None)])
