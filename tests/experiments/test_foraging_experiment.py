"""The experiment runner: registered as `mover experiment foraging`, seeded, JSON at the end."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

import experiments.foraging as fx
from mover.cli import UsageError


def parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    fx.register(parser.add_subparsers(dest="experiment"))
    return parser.parse_args(["foraging", *argv])


def test_table2_json_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["--table", "2", "--agents", "1,2", "--runs", "3", "--seed", "5", "--json", "--quiet"]
    args = parse([*argv, "--out", str(tmp_path)])
    assert args.func is fx.run
    assert args.func(args) == 0
    out = capsys.readouterr().out
    last = json.loads(out.strip().splitlines()[-1])
    assert last["seed"] == 5 and set(last["table2"]) == {"1", "2"}
    assert "Table 2" in out and "agent-steps/s" in out
    assert (tmp_path / "table2.png").stat().st_size > 0
    again = parse([*argv, "--out", str(tmp_path)])
    again.func(again)
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1]) == last  # seeded


def test_figure9_small(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = parse(["--table", "ants", "--sizes", "12", "--runs", "1", "--json", "--quiet",
                  "--out", str(tmp_path)])  # fmt: skip
    assert args.func(args) == 0
    last = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert set(last["fig9"]) >= {"cmarking", "ants"}
    assert (tmp_path / "fig9.png").exists()


def test_trial_is_a_pure_function_of_its_seeds() -> None:
    a = fx.run_trial(fx.SETUP2, 3, "cmarking", (1, 2, 0), (1, 2, 0, 3, 0), 100_000)
    b = fx.run_trial(fx.SETUP2, 3, "cmarking", (1, 2, 0), (1, 2, 0, 3, 0), 100_000)
    assert a == b and a.finished


def test_variants_reach_the_agents() -> None:
    base = fx.run_trial(fx.SETUP2, 3, "cmarking", (1, 2, 0), (1, 2, 0, 3, 0), 100_000)
    letter = fx.run_trial(
        fx.SETUP2, 3, "cmarking", (1, 2, 0), (1, 2, 0, 3, 0), 100_000, colour_source=False
    )
    assert letter.finished and letter != base


def test_per_trail_reading_reaches_the_agents(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    env, seed = (1, 2, 0), (1, 2, 0, 3, 0)
    base = fx.run_trial(fx.SETUP2, 3, "cmarking", env, seed, 100_000)
    per = fx.run_trial(fx.SETUP2, 3, "cmarking", env, seed, 100_000, trail_colours="per-trail")
    climb = fx.run_trial(fx.SETUP2, 3, "cmarking", env, seed, 100_000, trail_colours="per-trail",
                         climb_any=True)  # fmt: skip
    assert per.finished and climb.finished and len({base.iterations, per.iterations,
                                                    climb.iterations}) > 1  # fmt: skip
    argv = ["--table", "2", "--agents", "2", "--runs", "2", "--json", "--quiet",
            "--trail-colours", "per-trail", "--out", str(tmp_path)]  # fmt: skip
    args = parse(argv)
    args.func(args)
    out = capsys.readouterr().out
    assert "trail_colours per-trail" in out.splitlines()[0]
    assert json.loads(out.strip().splitlines()[-1])["trail_colours"] == "per-trail"


def test_default_json_names_no_new_reading(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = parse(["--table", "2", "--agents", "2", "--runs", "1", "--json", "--quiet",
                  "--out", str(tmp_path)])  # fmt: skip
    args.func(args)
    last = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert set(last) == {"seed", "runs", "until", "literal", "forget_at_base", "colour_on_move",
                         "table2"}  # fmt: skip


def test_agent_seeds_pair_draws_on_each_environment(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    one = ["--table", "2", "--agents", "1,3", "--runs", "4", "--seed", "5", "--json", "--quiet",
           "--out", str(tmp_path)]  # fmt: skip
    args = parse(one)
    args.func(args)
    single = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    args = parse([*one, "--agent-seeds", "3"])
    args.func(args)
    out = capsys.readouterr().out
    multi = json.loads(out.strip().splitlines()[-1])
    assert "4 envs x 3 seeds" in out and multi["agent_seeds"] == 3
    draws = multi["table2_draws"]
    assert [len(draws[k]) for k in ("1", "3")] == [3, 3]
    assert [draws[k][0] for k in ("1", "3")] == [single["table2"][k] for k in ("1", "3")]
    assert abs(multi["table2"]["1"] - sum(draws["1"]) / 3) < 0.1  # every run finished
    assert multi["table2_se"]["1"] > 0


@pytest.mark.parametrize(
    ("argv", "problem"),
    [
        (["--runs", "0"], "--runs must be from 1 to 100000, got 0"),
        (["--min-runs", "50", "--max-runs", "40"], "at most --max-runs"),
        (["--agents", "0,2"], "--agents must be positive"),
        (["--sizes", "3"], "--sizes at least 5"),
        (["--max-iterations", "0"], "--max-iterations must be positive"),
        (["--agent-seeds", "0"], "--agent-seeds must be positive"),
        (["--trail-colours", "per-trail", "--colour-on-move"], "not with --colour-on-move"),
    ],
)
def test_usage_errors(argv: list[str], problem: str) -> None:
    args = parse(argv)
    with pytest.raises(UsageError, match=problem):
        args.func(args)


def test_settings_are_a_frozen_record_not_the_namespace() -> None:
    args = parse(["--table", "2", "--agents", "1,3", "--runs", "4"])
    s = fx.settings(args)
    assert (s.table, s.agents, s.runs, s.tables) == ("2", (1, 3), 4, ["2"])
    assert fx.settings(parse([])).tables == ["1", "2", "ants", "3"]
    with pytest.raises(AttributeError):
        s.runs = 5  # type: ignore[misc]
    assert vars(args) == vars(parse(["--table", "2", "--agents", "1,3", "--runs", "4"]))


def test_model_fit_recovers_a_and_b_and_discovery_is_seeded() -> None:
    from experiments.foraging._model import ModelRow, discovery, fit

    rows = [ModelRow(k, fx.Row(str(k), [d]), [tb]) for k, d, tb in
            ((1, 100, 900), (2, 60, 450), (4, 40, 225))]  # fmt: skip
    f = fit(rows, {r.key: 0.5 * r.d.mean + 3.0 * r.tb_mean for r in rows})
    assert f is not None and abs(f.a - 0.5) < 1e-9 and abs(f.b - 3.0) < 1e-9 and f.rms < 1e-12
    g = fit(rows, {r.key: 3.0 * r.tb_mean - 0.1 * r.d.mean for r in rows})
    assert g is not None and g.a == 0.0 and g.b > 0  # a held at zero, not negative
    one, tb = discovery(fx.SETUP2, 2, (1, 2, 0), (1, 2, 0, 2, 2), 100_000)
    assert one.finished and one.iterations > 0 and tb > 0
    assert discovery(fx.SETUP2, 2, (1, 2, 0), (1, 2, 0, 2, 2), 100_000) == (one, tb)


def test_model_table_fits_stored_times(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    stored = tmp_path / "t2.txt"
    stored.write_text('report\n{"table2": {"1": 1500.0, "2": 800.0}}\n')
    argv = ["--table", "model", "--agents", "1,2", "--sizes", "12,25", "--runs", "2", "--quiet"]
    args = parse([*argv, "--json", "--fit", f"ours={stored}", "--out", str(tmp_path)])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    last = json.loads(out.strip().splitlines()[-1])
    assert set(last["model2"]["fits"]) == {"paper", "ours"} and "pooled" not in out
    assert "paper over Tables 1, 2, 3" in out
    bad = parse(["--table", "model", "--fit", f"x={tmp_path / 'none.txt'}"])
    with pytest.raises(UsageError, match="no file"):
        bad.func(bad)
