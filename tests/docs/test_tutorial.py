"""The tutorial (docs/tutorial.md), followed literally from an empty folder outside the repo.

Every code block of the page is used: a block whose first line is ``# file: PATH`` is written
to PATH in the tutorial's folder, and every ``sh`` block's commands are run in order, from a
temporary directory. Each command must be one this test knows how to run; ``pip install -e .``
is run as the same install made offline (``--no-index --no-build-isolation``, into a folder put
on ``PYTHONPATH``), since tests run without a network. So the program, its team file, its world
and its multi-process test are exactly the page's, and a page that drifts fails here.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]
TUTORIAL = ROOT / "docs" / "tutorial.md"
BLOCK = re.compile(r"^```(\w*)\n(.*?)^```$", re.MULTILINE | re.DOTALL)
FILE = re.compile(r"^# file: (\S+)\n")


def blocks(text: str) -> list[tuple[str, str]]:
    """The page's fenced code blocks as (language, body), in order."""
    return [(m.group(1), m.group(2)) for m in BLOCK.finditer(text)]


def test_every_block_of_the_tutorial_is_used() -> None:
    found = blocks(TUTORIAL.read_text())
    used = [lang for lang, body in found if lang == "sh" or FILE.match(body)]
    shown = [lang for lang, body in found if lang == "text"]  # output, to read
    assert len(used) + len(shown) == len(found) and len(used) >= 7


def test_the_tutorial_runs_from_an_empty_folder(tmp_path: Path) -> None:
    site = tmp_path / "site"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]),
    }
    for var in [v for v in env if v.startswith("MOVER_")]:
        del env[var]  # the tutorial's team comes from its team file alone
    cwd = tmp_path / "work"
    cwd.mkdir()
    outputs: dict[str, str] = {}
    for lang, body in blocks(TUTORIAL.read_text()):
        if (m := FILE.match(body)) is not None:
            path = cwd / m.group(1)
            assert path.parent.is_dir(), f"{m.group(1)}: the tutorial made no such folder"
            path.write_text(body)
            continue
        if lang != "sh":
            continue
        for line in body.splitlines():
            words = shlex.split(line, comments=True)
            if not words:
                continue
            if words[:2] == ["mkdir", "-p"]:
                for folder in words[2:]:
                    (cwd / folder).mkdir(parents=True)
            elif words[0] == "cd":
                cwd = cwd / words[1]
            elif words == ["pip", "install", "-e", "."]:
                pip = [sys.executable, "-m", "pip", "install", "-q", "--no-deps"]
                subprocess.run(
                    [*pip, "--no-build-isolation", "--no-index", "--target", str(site), "."],
                    cwd=cwd, check=True, timeout=120, capture_output=True,
                )  # fmt: skip
            elif words[0] == "mover" or words[:3] == ["python", "-m", "pytest"]:
                argv = [sys.executable, "-m", "mover", *words[1:]]
                if words[0] == "python":
                    argv = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *words[3:]]
                done = subprocess.run(
                    argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=240
                )
                output = done.stdout + done.stderr
                assert done.returncode == 0, f"{line}:\n{output[-4000:]}"
                outputs[line] = output
            else:
                pytest.fail(f"the tutorial runs {line!r}, which this test does not know")
    up = next(out for line, out in outputs.items() if "--exit-after-run" in line)
    assert up.count('"all_arrived": true') == 3, up[-3000:]
    assert len(set(re.findall(r'"first": "(\w+)"', up))) == 1, up[-3000:]
    tests = next(out for line, out in outputs.items() if "pytest" in line)
    assert "2 passed" in tests, tests[-3000:]
