"""The example of the library page (docs/reference/library.md) runs as printed."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from sim_hw import World
from tests.robots.conftest import robots_in
from tests.robots.test_search import QUADRANTS

PAGE = Path(__file__).resolve().parents[2] / "docs" / "reference" / "library.md"
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.MULTILINE | re.DOTALL)


async def test_the_quadrant_patrol_finds_the_crate_of_its_own_quadrant() -> None:
    (code,) = BLOCK.findall(PAGE.read_text())
    page: dict[str, Any] = {}
    exec(compile(code, str(PAGE), "exec"), page)
    server, robots = await robots_in(World(QUADRANTS, seed=2), {"r": {"pose": [3.0, 3.0, 0.0]}})
    found = await page["patrol"](robots["r"], 3)
    await server.door.aclose()
    assert found is not None and found.object_id == "north_east"
