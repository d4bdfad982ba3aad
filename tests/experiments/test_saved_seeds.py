"""Runs do not land in the repository by accident: a runner saves under ``out/`` unless told
``--save results/...``, and ``--saved`` without ``--seed`` says which seeds are saved."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from experiments._saved import default_save, saved_seeds, seeds_table
from experiments.eyebot import register, run


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="cmd"))
    return parser.parse_args(["eyebot", *argv])


def _save(folder: Path, point: str, *seeds: int) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    lines = [json.dumps({"seed": s, "run": k, "point": point}) for k, s in enumerate(seeds)]
    (folder / f"{point}.jsonl").write_text("\n".join([*lines, '{"cut']) + "\n")


def test_the_default_save_folder_is_outside_the_tracked_results() -> None:
    assert default_save("eyebot") == Path("out/eyebot/runs")
    assert _parse().save == Path("out/eyebot/runs")
    assert _parse("--save", "results/eyebot/runs").save == Path("results/eyebot/runs")


def test_saved_seeds_counts_each_seeds_runs_per_point(tmp_path: Path) -> None:
    _save(tmp_path, "a", 7, 7, 3)
    _save(tmp_path, "b", 7)
    assert saved_seeds(tmp_path) == {3: {"a": 1}, 7: {"a": 2, "b": 1}}
    assert saved_seeds(tmp_path / "none") == {}
    assert seeds_table(tmp_path / "none") == f"no runs saved in {tmp_path / 'none'}"


def test_saved_without_seed_lists_the_saved_seeds_and_makes_no_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _save(tmp_path / "runs", "cluttered_n1_shortest", 11, 11, 5)
    assert run(_parse("--saved", "--save", str(tmp_path / "runs"), "--no-plots")) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        f"seeds saved in {tmp_path / 'runs'} (pick one with --seed N):",
        "  5: 1 runs (cluttered_n1_shortest 1)",
        "  11: 2 runs (cluttered_n1_shortest 2)",
    ]
