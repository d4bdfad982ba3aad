"""A maze sweep on a Dask cluster (a ``dask scheduler`` and two ``dask worker`` processes on
127.0.0.1) saves the same runs as the local pool (apart from the wall-clock ``step_ms`` and
``time_s``), resumes as the pool does, loses no run when a worker is killed mid-sweep, and a run
that raises is named in one line with its seed; ``--executor dask`` with no address makes the
same runs on a ``LocalCluster``."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from experiments._common import Progress
from experiments._saved import Executor, JobFailed, Record, executor, run_pool
from experiments.maze import register, settings
from experiments.maze._trial import Job, describe, jobs, one_run, point_file
from mover._config import free_port

pytestmark = pytest.mark.processes
distributed = pytest.importorskip("distributed", reason="needs the dask extra: mover[dask]")

ROOT = Path(__file__).resolve().parents[2]
DASK = Path(sys.executable).with_name("dask")
SMALL = ("--seed", "5", "--agents", "1,3", "--size", "12", "--methods", "cu-lvp,nf")
CLOCKED = ("step_ms", "time_s")  # wall-clock figures: no two runs share them, on any executor


@contextmanager
def dask_cluster(
    logs: Path, *worker_args: str
) -> Iterator[tuple[str, list[subprocess.Popen[bytes]]]]:
    """A scheduler with two one-thread workers, all on 127.0.0.1, no dashboard: its address
    and the two workers' processes."""
    port = free_port()
    address = f"127.0.0.1:{port}"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    worker = [str(DASK), "worker", f"tcp://{address}", "--host", "127.0.0.1", "--nthreads", "1"]
    commands = [
        [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
        *[[*worker, "--no-dashboard", "--name", f"w{i}", *worker_args] for i in range(2)],
    ]
    procs: list[subprocess.Popen[bytes]] = []
    try:
        for i, command in enumerate(commands):
            with (logs / f"{i}.log").open("wb") as log:
                procs.append(subprocess.Popen(command, cwd=ROOT, env=env, stdout=log, stderr=log))
        with distributed.Client(f"tcp://{address}", timeout=30) as client:
            client.wait_for_workers(2, timeout=30)
        yield address, procs[1:]
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in reversed(procs):
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The address of a scheduler with two workers (each under a nanny)."""
    with dask_cluster(tmp_path_factory.mktemp("dask"), "--nworkers", "1") as (address, _):
        yield address


@pytest.fixture(scope="module")
def local_pool(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[str]]:
    """The small sweep's one run a point, made by the local pool: its saved lines."""
    local = tmp_path_factory.mktemp("local")
    assert _run("--runs", "1", "--workers", "2", "--save", str(local)) == 0
    return _saved(local)


def _run(*argv: str) -> int:
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="cmd"))
    args = parser.parse_args(["maze", *SMALL, "--no-plots", *argv])
    return int(args.func(args))


def _saved(folder: Path) -> dict[str, list[str]]:
    """Each point file's lines, sorted, the wall-clock figures left out."""
    files = {}
    for path in sorted(folder.glob("*.jsonl")):
        lines = []
        for line in path.read_text().splitlines():
            rec = json.loads(line)
            lines.append(json.dumps({k: v for k, v in rec.items() if k not in CLOCKED}))
        files[path.name] = sorted(lines)
    return files


def test_a_maze_sweep_on_dask_saves_the_local_pools_runs(scheduler: str, tmp_path: Path) -> None:
    local, dask = tmp_path / "local", tmp_path / "dask"
    assert _run("--runs", "2", "--workers", "2", "--save", str(local)) == 0
    assert _run("--runs", "1", "--executor", f"dask://{scheduler}", "--save", str(dask)) == 0
    assert sum(len(v) for v in _saved(dask).values()) == 2 * 2 * 2  # p, agents, methods
    made = {p.name: p.read_text() for p in dask.glob("*.jsonl")}
    assert _run("--runs", "2", "--executor", f"dask://{scheduler}", "--save", str(dask)) == 0
    for name, text in made.items():  # resumed: the first runs kept, the second appended
        assert (dask / name).read_text().startswith(text)
    assert _saved(dask) == _saved(local)
    assert sum(len(v) for v in _saved(local).values()) == 2 * 2 * 2 * 2


def explode(job: int) -> dict[str, int]:
    """A run that raises for job 3 (imported by the workers from this module)."""
    if job == 3:
        raise ValueError("no maze today")
    return {"run": job, "seed": 7}


@pytest.mark.parametrize("where", ["local", "dask"])
def test_a_run_that_raises_is_named_in_one_line(scheduler: str, where: str) -> None:
    on = executor(f"dask://{scheduler}" if where == "dask" else "local")
    with pytest.raises(JobFailed, match=r"^run 3 of seed 7 raised ValueError: no maze today$"):
        run_pool(
            list(range(6)),
            explode,
            workers=2,
            save_to=None,
            bar=Progress(6, enabled=False),
            status=str,
            on=on,
            describe=lambda job: f"run {job} of seed 7",
        )


def test_executor_is_read_from_the_command_line() -> None:
    assert executor("local") == Executor()
    assert executor("dask") == Executor("dask")
    assert executor("dask://10.0.0.5:8786") == Executor("dask", "tcp://10.0.0.5:8786")
    assert executor("dask://tls://h:1") == Executor("dask", "tls://h:1")
    for wrong in ("dusk", "dask://", "local://x"):
        with pytest.raises(argparse.ArgumentTypeError):
            executor(wrong)


def test_dask_with_no_address_makes_the_runs_on_a_local_cluster(
    local_pool: dict[str, list[str]], tmp_path: Path
) -> None:
    """``--executor dask``: a ``LocalCluster`` of ``--workers`` processes on 127.0.0.1."""
    assert _run("--runs", "1", "--executor", "dask", "--workers", "2", "--save", str(tmp_path)) == 0
    assert _saved(tmp_path) == local_pool


def slow_run(job: Job) -> Record:
    """A maze run that takes half a second at least (imported by the workers from here), so
    that a worker is killed while it holds one."""
    time.sleep(0.5)
    return one_run(job)


@pytest.mark.timeout(120)
def test_a_worker_killed_mid_sweep_loses_no_run(
    local_pool: dict[str, list[str]], tmp_path: Path
) -> None:
    """Two workers without a nanny (a killed one is not restarted); one is SIGKILLed when the
    first run comes back: the scheduler makes its runs on the other, and the saved runs are
    the local pool's."""
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="cmd"))
    with dask_cluster(tmp_path, "--no-nanny") as (address, workers):
        argv = ["maze", *SMALL, "--runs", "1", "--save", str(tmp_path / "dask")]
        s = settings(parser.parse_args([*argv, "--executor", f"dask://{address}"]))
        todo = jobs(s)
        made_at_kill: list[int] = []

        def kill_one(rec: Record) -> None:
            if not made_at_kill:
                workers[0].kill()
                made_at_kill.append(1)

        started = time.monotonic()
        made = run_pool(
            todo,
            slow_run,
            workers=2,
            save_to=lambda r: point_file(s, r["method"], r["agents"], r["p"]),
            bar=Progress(len(todo), enabled=False),
            status=str,
            on=s.executor,
            describe=describe,
            each=kill_one,
        )
        print(f"{made} runs in {time.monotonic() - started:.1f} s, one worker killed after 1")
        assert workers[0].wait(timeout=10) == -signal.SIGKILL
        assert workers[1].poll() is None  # the other carried on
    assert made == len(todo) == 8
    assert _saved(tmp_path / "dask") == local_pool
