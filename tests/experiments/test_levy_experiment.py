"""The Lévy runner: seeded trials, the arena as a world file, its command line (tables with
the paper's ordering, saved runs that a later run adds to, JSON, figures) and usage errors."""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import replace
from pathlib import Path

import pytest

from experiments.levy import (
    Setup,
    arena,
    cauchy_steps,
    paired,
    points,
    register,
    run_trial,
    run_world,
    settings,
    step_stats,
    step_table,
    table,
    theory,
    world_data,
)
from mover.cli import UsageError
from sim_hw.continuous import load_world

pytestmark = pytest.mark.processes

SMALL = replace(Setup(), size=8.0, obstacles=3, max_time=300.0)


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="cmd"))
    return parser.parse_args(["levy", *argv])


def test_a_trial_is_a_function_of_its_seeds() -> None:
    a = run_trial(SMALL, "L+P", 3, 2, 4, 1)
    b = run_trial(SMALL, "L+P", 3, 2, 4, 1)
    strip = ("wall_s",)
    assert {k: v for k, v in a.items() if k not in strip} == {
        k: v for k, v in b.items() if k not in strip
    }
    assert a["time"] is not None and a["time"] == a["found"][-1] and len(a["found"]) == 2
    assert a["robot_s"] == pytest.approx(3 * a["sim_s"])


def test_the_arena_keeps_targets_and_robots_clear_and_is_shared_by_methods() -> None:
    spec = arena(Setup(), 10, 8, 3, 0)
    assert spec.size == (20.0, 20.0) and len(spec.obstacles) > 0
    assert len(spec.markers) == 8 and all(m.hears > Setup().walk.sense_range for m in spec.markers)
    assert sorted(spec.robots) == [f"r{i:02d}" for i in range(10)]
    for m in spec.markers:
        for n in spec.markers:
            assert m is n or math.dist(m.center, n.center) >= 2.0
    assert arena(Setup(), 10, 8, 3, 0) == spec
    assert arena(Setup(), 10, 8, 3, 1) != spec
    # the same obstacles for every target count of run 0
    assert arena(Setup(), 10, 4, 3, 0).obstacles == spec.obstacles


def test_the_arena_as_a_world_file_loads_back(tmp_path: Path) -> None:
    spec = arena(SMALL, 3, 2, 4, 1)
    path = tmp_path / "levy.json"
    path.write_text(json.dumps(world_data(spec)))
    loaded = load_world(path)
    assert [m.center for m in loaded.markers] == [m.center for m in spec.markers]
    assert [m.hears for m in loaded.markers] == [m.hears for m in spec.markers]
    assert len(loaded.obstacles) == len(spec.obstacles)
    for rid, robot in spec.robots.items():
        assert loaded.robots[rid].pose == pytest.approx(robot.pose)
    assert loaded.robot.camera == spec.robot.camera
    assert run_world(loaded, "FL", SMALL, [1])["time"] is not None


def test_runner_tables_save_and_add_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    save = tmp_path / "runs"
    common = ("--seed", "9", "--sweep", "fig8", "--targets", "1", "--save", str(save))
    args = _parse(*common, "--runs", "2", "--out", str(tmp_path), "--methods", "L,L+P")
    assert args.func(args) == 0
    out, err = capsys.readouterr()
    assert out.startswith("seed: 9\n")
    assert "search time (s) vs number of targets, 10 robots (Fig. 8)" in out
    assert "L+P < L < FL" in out  # the paper's ordering, beside the measured one
    assert "robot-seconds per wall second" in out and "4/4 done" in err  # plain off a tty
    assert "paired by run" in out and "L+P - L" in out
    assert (tmp_path / "levy_fig8.png").stat().st_size > 0
    files = sorted(p.name for p in save.iterdir())
    assert files == ["L+P_r10_t1_a1.jsonl", "L_r10_t1_a1.jsonl"]
    first = (save / "L_r10_t1_a1.jsonl").read_text().splitlines()
    assert len(first) == 2
    more = _parse(*common, "--runs", "3", "--no-plots", "--json", "--methods", "L,L+P")
    assert more.func(more) == 0
    out, _ = capsys.readouterr()
    assert "fig8: 2 runs made" in out  # only run 2 of each method was missing
    lines = (save / "L_r10_t1_a1.jsonl").read_text().splitlines()
    assert lines[:2] == first and len(lines) == 3
    data = json.loads(out.strip().splitlines()[-1])
    assert data["seed"] == 9 and sorted(r["run"] for r in data["runs"]) == [0, 0, 1, 1, 2, 2]


def test_censored_runs_are_marked_and_the_alpha_sweep_names_the_theory(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = _parse(
        "--seed", "2", "--sweep", "fig9,alpha", "--robots", "1", "--alphas", "0.5,2",
        "--runs", "1", "--max-time", "5", "--no-save", "--no-plots", "--workers", "1", "--quiet",
    )  # fmt: skip
    assert args.func(args) == 0
    out = capsys.readouterr()[0]
    assert "saturation (Fig. 9)" in out and "destructive search" in out
    assert "c " in out or "c\n" in out  # a censored cell


def test_table_and_theory_by_hand() -> None:
    rec = [
        {"method": m, "targets": 4, "time": t, "robots": 10, "alpha": 1.0, "run": k}
        for m, t, k in (("FL", 30.0, 0), ("L", 20.0, 0), ("L+P", 10.0, 0), ("L+P", 14.0, 1))
    ]
    text = table(rec, "targets", "t", Setup())
    assert "12.0 ±   2.8 (  2.0)" in text and text.count("L+P < L < FL") == 2
    diffs = paired(rec, "targets", Setup())  # run 1 has no L to pair with
    assert "-10.0 ±  nan (n   1)" in diffs and "-10.0" in diffs.splitlines()[-1]
    assert "μ = 1.90" in theory(Setup(), 8)


@pytest.mark.parametrize(
    "argv",
    [
        ("--runs", "0"),
        ("--workers", "0"),
        ("--targets", "0"),
        ("--alphas", "0.5,2.5"),
        ("--alpha", "0"),
        ("--max-time", "-1"),
        ("--rho0", "0"),
        ("--k-rep", "-1"),
        ("--steps", "0"),
        ("--check-robots", "0"),
    ],
)
def test_usage_errors(argv: tuple[str, ...]) -> None:
    args = _parse(*argv, "--no-save")
    with pytest.raises(UsageError):
        args.func(args)


def test_runs_of_other_settings_are_saved_apart(tmp_path: Path) -> None:
    args = _parse("--save", str(tmp_path / "runs"), "--rho0", "3", "--k-sig", "20")
    s = settings(args)
    assert s.save == tmp_path / "runs-rho0=3,k_sig=20"
    assert s.setup.walk.rho0 == 3.0 and s.setup.walk.k_sig == 20.0
    plain = settings(_parse("--save", str(tmp_path / "runs"), "--alpha", "1.5"))
    assert plain.save == tmp_path / "runs" and plain.setup.tag() == ""


def test_the_capped_mean_step_measured_from_the_generator_is_the_closed_form() -> None:
    median, mean = cauchy_steps(1.0, 20.0)
    assert median == 1.0 and mean == pytest.approx(2.5440, abs=1e-4)
    got = step_stats(Setup(), draws=100_000, seed=1)
    assert got[0] == pytest.approx(1.0, abs=0.03) and got[1] == pytest.approx(mean, abs=0.05)
    assert cauchy_steps(2.0, 40.0) == pytest.approx((2.0, 2 * mean))


def test_the_step_table_pairs_fl_at_each_step_with_l_by_hand() -> None:
    rec = [
        {"method": m, "robots": 10, "targets": 8, "alpha": 1.0, "fixed": f, "run": k, "time": t}
        for m, f, k, t in (
            ("L", None, 0, 100.0),
            ("L", None, 1, 110.0),
            ("L", None, 2, 90.0),
            ("FL", 1.0, 0, 200.0),
            ("FL", 1.0, 1, 205.0),
            ("FL", 1.0, 2, 195.0),
            ("FL", 2.5, 0, 95.0),
            ("FL", 2.5, 1, 120.0),
            ("FL", 2.5, 2, 80.0),
        )
    ]
    text = step_table(rec, Setup())
    assert "-100.0 ±  2.9 (n   3)" in text  # L - FL(1 m): -100, -95, -105
    assert "1 m L < FL, 2.5 m L ≈ FL" in text


def test_the_checks_sweeps_name_their_points_and_keep_the_default_fl_point() -> None:
    s = settings(_parse("--steps", "1,2.5", "--check-robots", "10", "--no-save"))
    names = [p.name for p in points(s, "step")]
    assert names == ["L_r10_t8_a1", "L+P_r10_t8_a1", "FL_r10_t8_a1", "FL_r10_t8_a1_f2.5"]
    assert [p.method for p in points(s, "parts")] == ["L", "L+F", "L+S", "L+P"]
    assert [p.method for p in points(s, "fig4")] == ["FL", "FL+S", "L", "L+S", "L+P"]


def test_the_checks_sweeps_run_save_and_tabulate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    save = tmp_path / "runs"
    args = _parse(
        "--seed", "5", "--sweep", "step,parts,fig4", "--check-robots", "3", "--steps", "2.5",
        "--runs", "2", "--max-time", "30", "--save", str(save), "--workers", "1", "--quiet",
    )  # fmt: skip
    assert args.func(args) == 0
    out = capsys.readouterr()[0]
    assert "mean 2.54" in out and "closed form" in out
    assert "L+P - L+F - L+S + L" in out and "FL+S - FL" in out
    files = sorted(p.name for p in save.iterdir())
    assert "FL_r3_t8_a1_f2.5.jsonl" in files and "FL+S_r3_t8_a1.jsonl" in files
    assert "L+F_r3_t8_a1.jsonl" in files and "L+S_r3_t8_a1.jsonl" in files
    line = json.loads((save / "FL_r3_t8_a1_f2.5.jsonl").read_text().splitlines()[0])
    assert line["fixed"] == 2.5 and line["method"] == "FL"
