"""The runners' pool of workers, as the ``mover`` command runs it: the pool's end is quiet.

A forked worker inherits the command's SIGTERM handler (``mover.cli.interrupt_on_sigterm``);
the pool stops its workers with SIGTERM as it closes, which printed a traceback per worker at
the end of every experiment until the workers were given their own signal handling."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = textwrap.dedent(
    """
    import json, sys, time
    from pathlib import Path
    from mover.cli import interrupt_on_sigterm
    from experiments._common import Progress
    from experiments._saved import load_runs, run_pool

    def work(job):  # the last job ends while the other worker waits for one: as in a sweep
        rec = json.loads(job)
        time.sleep(0.1 + 0.1 * (rec["run"] % 2))
        return rec

    interrupt_on_sigterm()
    for pool in range(3):
        out = Path(sys.argv[1]) / f"{pool}.jsonl"
        jobs = [json.dumps({"seed": 7, "run": i}) for i in range(5)]
        made = []
        n = run_pool(jobs, work, workers=2, save_to=lambda rec: out,
                     bar=Progress(5, enabled=False), status=str, each=made.append)
        assert n == len(made)
        print(sorted(r["run"] for r in made), sorted(load_runs(out, 7)))
    """
)


def test_a_pool_run_by_the_command_ends_without_a_traceback(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["[0, 1, 2, 3, 4] [0, 1, 2, 3, 4]"] * 3
    assert done.stderr == ""  # no worker's traceback
