"""The python blocks of docs/programs.md and docs/sweeps.md: each is run here, or its page says,
just before it, that it is an illustration no test runs (it cannot run alone)."""

from __future__ import annotations

import re
from pathlib import Path
from types import SimpleNamespace
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
PAGES = ("programs.md", "sweeps.md")
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.MULTILINE | re.DOTALL)
ILLUSTRATION = "is an illustration"


def python_blocks(page: str) -> list[tuple[str, str]]:
    """The page's python blocks: (the paragraph before the block, its code)."""
    text = (ROOT / "docs" / page).read_text()
    before = [text[: m.start()].rstrip().rsplit("\n\n", 1)[-1] for m in BLOCK.finditer(text)]
    return list(zip(before, BLOCK.findall(text), strict=True))


RUN = {("programs.md", 0)}
"""The blocks run here (page, index among its python blocks)."""


def test_every_python_block_is_run_or_marked_as_an_illustration() -> None:
    for page in PAGES:
        for i, (before, _) in enumerate(python_blocks(page)):
            assert (page, i) in RUN or ILLUSTRATION in before, (
                f"docs/{page}: python block {i + 1} is neither run by tests/docs/"
                f"test_page_examples.py nor said to be an illustration just before it"
            )
    assert all(i < len(python_blocks(page)) for page, i in RUN)


async def test_the_program_of_the_programs_page_reports_and_returns_its_result() -> None:
    (_, code), *_ = python_blocks("programs.md")
    page: dict[str, Any] = {}
    exec(compile(code, "docs/programs.md", "exec"), page)
    reports: list[str] = []

    async def report(phase: str, **info: Any) -> None:
        reports.append(phase)

    robot, team = SimpleNamespace(id="ernst"), SimpleNamespace(report=report)
    assert await page["my_program"](robot, team) == {"me": "ernst", "distance": 1.0}
    assert await page["my_program"](robot, team, distance=2.5) == {"me": "ernst", "distance": 2.5}
    assert reports == ["started", "started"]
