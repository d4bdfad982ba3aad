"""The maze runner's command line: tables, ranking, JSON, maze files, its usage errors."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from experiments.maze import register
from mover.cli import UsageError
from sim_hw.grid import generate_maze, save_maze

RESULTS = Path(__file__).resolve().parents[2] / "results"


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="cmd"))
    return parser.parse_args(["maze", *argv])


SMALL = ("--runs", "2", "--seed", "5", "--agents", "1,3", "--size", "12", "--methods", "cu-lvp,nf")


def test_runner_prints_tables_ranking_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = _parse(
        *SMALL,
        "--out",
        str(tmp_path),
        "--json",
    )
    assert args.func(args) == 0
    out, err = capsys.readouterr()
    assert out.startswith("seed: 5\n")
    assert "exploration rounds — obstacle probability 0.85" in out
    assert "ranking:" in out
    assert "16/16 done" in err  # progress as plain lines off a terminal
    data = json.loads(out.strip().splitlines()[-1])
    assert len(data["runs"]) == 2 * 2 * 2 * 2
    assert (tmp_path / "maze_metrics.png").stat().st_size > 0
    assert (tmp_path / "maze_composite.png").exists()
    again = _parse(
        *SMALL,
        "--no-plots",
        "--json",
    )
    again.func(again)
    rerun = json.loads(capsys.readouterr()[0].strip().splitlines()[-1])
    strip = [{k: v for k, v in r.items() if k not in ("step_ms", "time_s")} for r in data["runs"]]
    assert strip == [
        {k: v for k, v in r.items() if k not in ("step_ms", "time_s")} for r in rerun["runs"]
    ]


def test_runner_on_a_maze_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "m.json"
    save_maze(path, generate_maze(12, 0.5, np.random.default_rng(2), n_starts=3))
    args = _parse(
        "--maze",
        str(path),
        "--runs",
        "1",
        "--agents",
        "3",
        "--seed",
        "1",
        "--methods",
        "cu-lvp",
        "--no-plots",
        "--json",
    )
    assert args.func(args) == 0
    runs = json.loads(capsys.readouterr()[0].strip().splitlines()[-1])["runs"]
    assert runs[0]["complete"]
    assert runs[0]["agents"] == 3
    assert runs[0]["p"] is None
    bad = _parse("--maze", str(path), "--agents", "4", "--no-plots")
    with pytest.raises(UsageError, match="3 starts, 4 agents asked"):
        bad.func(bad)


def test_exchanges_must_be_positive() -> None:
    bad = _parse("--exchanges", "0", "--no-plots")
    with pytest.raises(UsageError, match="--exchanges must be positive"):
        bad.func(bad)


def test_python_m_experiments_maze_prints_a_usage_error_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from experiments.cli import main

    assert main("maze", register, ["--load", str(tmp_path / "none.json"), "--no-plots"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("python -m experiments.maze: ") and "no JSON line of runs" in err
    assert "\n" not in err
    assert main("maze", register, ["--runs", "1", "--size", "8", "--agents", "1", "--seed",
                                   "3", "--methods", "nf", "--no-plots"]) == 0  # fmt: skip
    assert capsys.readouterr().out.startswith("seed: 3\n")


def test_settings_come_from_the_command_line_once() -> None:
    from experiments.maze import settings

    args = _parse("--runs", "3", "--hedac-runs", "1", "--agents", "2,4", "--no-plots")
    s = settings(args)
    assert (s.runs, s.runs_for("hedac"), s.runs_for("nf"), s.agents, s.out) == (
        3, 1, 3, (2, 4), None,
    )  # fmt: skip
    assert args.seed is None and 0 <= s.seed < 2**32  # a random seed, not written onto args


def test_partition_option_names_the_saved_runs_apart(tmp_path: Path) -> None:
    from experiments.maze import settings
    from experiments.maze._trial import point_file, run_trial

    plain = settings(_parse("--partition", "voronoi", "--save", str(tmp_path), "--no-plots"))
    balanced = settings(_parse("--save", str(tmp_path), "--no-plots"))
    assert (plain.partition, balanced.partition) == ("voronoi", "balanced")
    assert point_file(plain, "cu-lvp", 8, 0.85).name == "cu-lvp-n8-s30-p0.85-x3-voronoi.jsonl"
    assert point_file(balanced, "cu-lvp", 8, 0.85).name == "cu-lvp-n8-s30-p0.85-x3.jsonl"
    assert point_file(plain, "nf", 8, 0.85) == point_file(balanced, "nf", 8, 0.85)
    with pytest.raises(SystemExit):
        _parse("--partition", "square")
    # the option reaches the agents: 8 agents' runs differ on a maze with unequal regions
    maze = generate_maze(30, 0.85, np.random.default_rng(5), n_starts=8)
    runs = [
        run_trial(maze, 8, "cu-lvp", np.random.SeedSequence(1), partition=p)["cost"]
        for p in ("voronoi", "balanced")
    ]
    assert runs[0] != runs[1]
    nf = [
        run_trial(maze, 8, "nf", np.random.SeedSequence(1), partition=p)
        for p in ("voronoi", "balanced")
    ]
    assert (nf[0]["rounds"], nf[0]["cost"]) == (nf[1]["rounds"], nf[1]["cost"])  # plain both


def test_news_off_makes_the_stored_cu_lvp_runs_again(tmp_path: Path) -> None:
    """``--news off`` (with the plain partition) is CU-LVP as the six-method tables stored it
    (``results/maze/runs_cu-lvp.txt``, made before the balanced regions and the news): its
    runs are made again, every figure but the wall-clock ones, and saved apart."""
    from experiments.maze import settings
    from experiments.maze._trial import one_run, point_file

    stored = RESULTS / "maze" / "runs_cu-lvp.txt"
    runs = json.loads(stored.read_text().splitlines()[-1])["runs"]
    argv = ("--seed", "2026", "--agents", "1,2,4,6,8,10,15,20", "--methods", "cu-lvp")
    old = settings(_parse(*argv, "--partition", "voronoi", "--news", "off", "--no-plots"))
    new = settings(_parse(*argv, "--no-plots"))
    assert (old.news, new.news) == ("off", "on")
    old_save = settings(_parse("--news", "off", "--save", str(tmp_path), "--no-plots"))
    assert point_file(old_save, "cu-lvp", 8, 0.85).name == "cu-lvp-n8-s30-p0.85-x3-nonews.jsonl"
    assert point_file(old_save, "nf", 8, 0.85).name == "nf-n8-s30-p0.85-x3.jsonl"
    clock = {"step_ms", "time_s"}
    for want in [r for r in runs if r["run"] == 0 and r["agents"] in (4, 8)]:
        job = (old, want["p"], 0, want["agents"], "cu-lvp")
        made = one_run(job)
        assert {k: v for k, v in made.items() if k not in clock | {"seed"}} == {
            k: v for k, v in want.items() if k not in clock
        }
        assert one_run((new, want["p"], 0, want["agents"], "cu-lvp"))["rounds"] > 0


def test_news_whole_makes_the_stored_runs_of_the_whole_news_again(tmp_path: Path) -> None:
    """``--news whole`` is CU-LVP as ``results/maze/v2/runs_cu-lvp_wholenews.txt`` stored it (every
    message passing on all the news, before only what changed was): its runs are made again,
    every figure but the wall-clock ones, and saved apart."""
    from experiments.maze import settings
    from experiments.maze._trial import one_run, point_file

    stored = RESULTS / "maze" / "v2" / "runs_cu-lvp_wholenews.txt"
    runs = json.loads(stored.read_text().splitlines()[-1])["runs"]
    argv = ("--seed", "2026", "--agents", "1,2,4,6,8,10,15,20", "--methods", "cu-lvp")
    whole = settings(_parse(*argv, "--news", "whole", "--no-plots"))
    saved = settings(_parse("--news", "whole", "--save", str(tmp_path), "--no-plots"))
    assert point_file(saved, "cu-lvp", 8, 0.85).name == "cu-lvp-n8-s30-p0.85-x3-wholenews.jsonl"
    clock = {"step_ms", "time_s"}
    for want in [r for r in runs if r["run"] == 0 and r["agents"] in (4, 8)]:
        made = one_run((whole, want["p"], 0, want["agents"], "cu-lvp"))
        assert {k: v for k, v in made.items() if k not in clock | {"seed"}} == {
            k: v for k, v in want.items() if k not in clock | {"seed"}
        }


def test_compare_reference_pairs_runs_per_maze(tmp_path: Path) -> None:
    from experiments.maze.compare_reference import table

    (tmp_path / "ours" / "7").mkdir(parents=True)
    ours = [{"run": k, "rounds": r} for k, r in enumerate((70, 80, 90))]
    theirs = [{"p": 0.85, "agents": 8, "run": k, "rounds": r} for k, r in enumerate((75, 80))]
    theirs.append({"p": 0.15, "agents": 8, "run": 0, "rounds": 50})
    path = tmp_path / "ours" / "7" / "cu-lvp-n8-s30-p0.85-x3.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in ours))
    (tmp_path / "ref-s7.jsonl").write_text("".join(json.dumps(r) + "\n" for r in theirs))
    row = next(line for line in table(tmp_path / "ours", tmp_path, (7,)).splitlines()[2:]
               if line.startswith("| 0.85 | 8 |"))  # fmt: skip
    # runs 0 and 1 pair (run 2 has no reference): differences -5 and 0
    assert row == (
        "| 0.85 | 8 | -2.5 ± 2.5 (2) | **-2.5 ± 2.5 (2)** | 75.0 / 77.5 | 3.2 % | 1 / 1 / 0 |"
    )
