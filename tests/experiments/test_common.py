"""The runners' shared helpers: comma lists, mean ± sd / se, the progress line."""

from __future__ import annotations

import argparse
import math

import pytest

from experiments._common import Progress, comma_list, plus_minus, summary


def test_comma_lists_parse_check_and_refuse_empty() -> None:
    assert comma_list(int)("4, 8,") == [4, 8]
    assert comma_list(str, ["nf", "hedac"])("hedac,nf") == ["hedac", "nf"]
    with pytest.raises(argparse.ArgumentTypeError, match="unknown 'bso'; choose from nf, hedac"):
        comma_list(str, ["nf", "hedac"])("nf,bso")
    with pytest.raises(argparse.ArgumentTypeError, match="empty"):
        comma_list(int)(" , ")
    with pytest.raises(argparse.ArgumentTypeError, match="invalid literal"):
        comma_list(int)("4,x")


def test_summary_mean_sd_se() -> None:
    s = summary([1, 2, 3, 4])
    assert (s.n, s.mean) == (4, 2.5)
    assert s.sd == pytest.approx(math.sqrt(5 / 3))  # sample standard deviation
    assert s.se == pytest.approx(s.sd / 2) and s.rel_se == pytest.approx(s.se / 2.5)
    assert summary([1, 2, 3, 4], ddof=0).sd == pytest.approx(math.sqrt(1.25))
    one = summary([7])
    assert one.mean == 7 and math.isnan(one.sd) and math.isnan(one.se) and one.rel_se == math.inf
    assert summary([7], ddof=0).sd == 0.0
    assert math.isnan(summary([]).mean)


def test_plus_minus_formats() -> None:
    assert plus_minus(12.345, 1.5, ".2f") == "12.35 ± 1.50"
    assert plus_minus(13091.2, 4248.5, "9.1f", "7.1f") == "  13091.2 ± 4248.5"


def test_progress_draws_on_stderr_and_ends_the_line(capsys: pytest.CaptureFixture[str]) -> None:
    bar = Progress(4, "table2", width=8, terminal=True)
    for k in range(1, 5):
        bar.update(k, f"run {k}")
    bar.close(4, "done")
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("\rtable2") and "[##......]    1/4" in err  # drawn once, then throttled
    assert err.rstrip().endswith("done") and "[########]    4/4" in err and err.endswith("\n")
    Progress(4, enabled=False).close(4)
    assert capsys.readouterr().err == ""


def test_progress_off_a_terminal_is_plain_lines(capsys: pytest.CaptureFixture[str]) -> None:
    bar = Progress(20, "fig2", terminal=False)
    for k in range(1, 21):
        bar.update(k, f"run {k}")
    bar.close(20, "done")
    lines = capsys.readouterr().err.splitlines()
    assert "\r" not in "".join(lines) and "[" not in "".join(lines)
    assert lines[0].startswith("fig2: 1/20 done") and lines[-1].startswith("fig2: 20/20 done")
    assert len(lines) == 12  # the first, one a tenth of the work, and the last again at close
