"""The eye-bot runner: its command line, the tables and figures, saved runs that a later
invocation adds to, and usage errors."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from experiments.eyebot import register, run, settings
from mover.cli import UsageError

pytestmark = pytest.mark.processes


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="cmd"))
    return parser.parse_args(["eyebot", *argv])


def test_the_runner_prints_tables_saves_runs_and_adds_to_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    save = tmp_path / "runs"
    argv = ["--figure", "fig2", "--runs", "1", "--duration", "80", "--seed", "3", "--quiet"]
    argv += ["--save", str(save), "--out", str(tmp_path / "out"), "--json"]
    assert run(_parse(*argv)) == 0
    first = capsys.readouterr().out
    assert "seed: 3" in first and "Fig. 2, cluttered arena" in first
    assert "fig2: 12 runs made" in first
    assert (tmp_path / "out" / "eyebot_fig2.png").stat().st_size > 0
    # runs of another duration than the paper's are kept apart
    assert f"runs saved in: {save}-duration=80" in first
    files = sorted(p.name for p in Path(f"{save}-duration=80").iterdir())
    assert "cluttered_n1_shortest.jsonl" in files and len(files) == 12
    # the same seed again makes no run; one more run per point makes 12
    assert run(_parse(*argv)) == 0
    again = capsys.readouterr().out
    assert "fig2: 0 runs made" in again

    def runs(out: str) -> list[dict[str, object]]:
        return sorted(json.loads(out.splitlines()[-1])["runs"], key=lambda r: str(r["point"]))

    assert runs(first) == runs(again)
    # --saved reports what is saved and makes none, however many runs are asked for
    assert run(_parse(*[a if a != "1" else "5" for a in argv], "--saved")) == 0
    saved = capsys.readouterr().out
    assert "fig2: 0 runs made" in saved and runs(saved) == runs(first)
    assert run(_parse(*[a if a != "1" else "2" for a in argv])) == 0
    assert "fig2: 12 runs made" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--runs", "0"], "--runs must be from 1"),
        (["--workers", "0"], "--workers must be from 1"),
        (["--duration", "nan"], "--duration must be from 10"),
        (["--duration", "1e9"], "--duration must be from 10"),
        (["--saved", "--no-save"], "cannot go with --no-save"),
        (["--eyebot-period", "0.01"], "--eyebot-period must be from 0.1"),
        (["--eyebot-period", "inf"], "--eyebot-period must be from 0.1"),
    ],
)
def test_bad_settings_are_one_line_errors(argv: list[str], message: str) -> None:
    with pytest.raises(UsageError, match=message):
        settings(_parse(*argv))


def test_an_unknown_figure_is_refused_by_the_parser(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        _parse("--figure", "fig9")
    assert "unknown 'fig9'" in capsys.readouterr().err


def test_old_readings_are_options_whose_runs_are_saved_apart(tmp_path: Path) -> None:
    new = settings(_parse("--save", str(tmp_path / "runs")))
    assert new.save == tmp_path / "runs" and new.old() == []
    old = settings(
        _parse(
            *("--save", str(tmp_path / "runs"), "--eyebot-period", "1", "--theta-f", "any"),
            *("--head-on", "right", "--eyebots-over-walls"),
        )
    )
    assert old.period == 1.0 and old.head_on_right and old.over_walls
    assert old.save == tmp_path / "runs-period=1-reading=any-head-on=right-over-walls"


def test_points_can_be_narrowed_and_a_choice_of_none_is_an_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["--figure", "fig2", "--runs", "1", "--duration", "30", "--seed", "3", "--quiet"]
    argv += [
        "--save",
        str(tmp_path / "runs"),
        "--no-plots",
        "--footbots",
        "2",
        "--ways",
        "learning",
    ]
    assert run(_parse(*argv)) == 0
    out = capsys.readouterr().out
    assert "fig2: 1 runs made" in out and "every run counted" in out
    with pytest.raises(UsageError, match="no point with these --footbots"):
        run(_parse(*argv[:-4], "--footbots", "7"))
