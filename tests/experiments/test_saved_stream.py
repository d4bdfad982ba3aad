"""``run_pool`` keeps nothing of a run: each record goes to its file as it comes, then to the
caller's ``each`` (a running aggregate, :class:`experiments._saved.Made`), and is dropped."""

from __future__ import annotations

import gc
import json
import weakref
from pathlib import Path

from experiments._common import Progress
from experiments._saved import Made, load_runs, run_pool


class Rec(dict[str, object]):
    """A record that can be watched (a plain dict takes no weak reference)."""


def test_each_run_is_saved_as_it_comes_and_none_is_kept(tmp_path: Path) -> None:
    out = tmp_path / "point.jsonl"
    alive: list[weakref.ref[Rec]] = []

    def work(run: int) -> Rec:
        saved = out.read_text().splitlines() if out.exists() else []
        assert [json.loads(line)["run"] for line in saved] == list(range(run))  # streamed
        rec = Rec(seed=7, run=run, wall_s=0.5, big=list(range(1000)))
        alive.append(weakref.ref(rec))
        return rec

    made = Made(wall_s=lambda r: float(r["wall_s"]))
    n = run_pool(
        list(range(6)),
        work,
        workers=1,
        save_to=lambda rec: out,
        bar=Progress(6, enabled=False),
        status=str,
        each=made,
    )
    gc.collect()
    assert n == made.runs == 6
    assert made.sums == {"wall_s": 3.0}
    assert [ref() for ref in alive] == [None] * 6  # no record held after the sweep
    assert sorted(load_runs(out, 7)) == list(range(6))
