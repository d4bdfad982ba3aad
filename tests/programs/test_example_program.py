"""The template of a program of one's own (examples/my_program): built and installed as a user
would (its own pyproject.toml, the mover.programs entry point), then its own test run, which
uses mover's pytest plugin with real processes."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "my_program"


def test_the_example_program_builds_installs_and_passes_its_own_test(tmp_path: Path) -> None:
    source = tmp_path / "my_program"
    shutil.copytree(EXAMPLE, source)
    site = tmp_path / "site"
    pip = [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation"]
    subprocess.run(
        [*pip, "--no-index", "--target", str(site), str(source)],
        check=True,
        timeout=120,
        capture_output=True,
    )
    assert list(site.glob("mover_example_race-*.dist-info"))
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]),
    }
    listed = subprocess.run(
        [sys.executable, "-c", "import programs; print(sorted(programs.installed()))"],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert "race" in listed.stdout  # found through the entry point, as mover run would
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(source / "tests")],
        cwd=tmp_path,  # not the example's directory: paths are relative to the test file
        env=env,
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    assert "1 passed" in result.stdout
