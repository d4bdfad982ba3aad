"""The reference pages name every key the readers know: team files, world files, a recording.

Each reader asks its tables for their keys through ``mover._tables.Table``; here that class is
watched while every team and world file of the repository is read, and each key it knows is
looked for on its page as `` `key` ``. The formats page is held to a recording's header and a
world's snapshot, made in-process. And every public name has a docstring (docs/_hooks.py).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

import pytest

from mover import _tables
from mover._up._teamfile import load_team
from sim_hw.continuous import World, load_world
from sim_hw.continuous._record import scene_header
from tests.helpers.docs_hooks import docs_hooks

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = ROOT / "docs" / "reference"


def _known_keys(monkeypatch: pytest.MonkeyPatch) -> set[str]:
    known: set[str] = set()
    only = _tables.Table.only
    read = _tables.Table.has

    def watched_only(self: _tables.Table, keys: Iterable[str], **kw: str | None) -> None:
        keys = list(keys)
        known.update(keys)
        only(self, keys, **kw)

    def watched_has(self: _tables.Table, key: str) -> bool:
        known.add(key)
        return read(self, key)

    monkeypatch.setattr(_tables.Table, "only", watched_only)
    monkeypatch.setattr(_tables.Table, "has", watched_has)
    return known


def _missing(keys: Iterable[str], page: Path) -> list[str]:
    text = page.read_text()
    return sorted(k for k in keys if not re.search(rf"(`|`\[|`\[\[){re.escape(k)}\b", text))


def test_every_public_name_has_a_docstring() -> None:
    assert docs_hooks().undocumented() == []


def test_the_team_file_page_names_every_key(monkeypatch: pytest.MonkeyPatch) -> None:
    known = _known_keys(monkeypatch)
    for path in sorted((ROOT / "teams").glob("*.toml")):
        load_team(path)
    assert {"team", "world", "robots", "program", "names", "survivors"} <= known
    assert _missing(known, REFERENCE / "team-file.md") == []


def test_the_world_file_page_names_every_key(monkeypatch: pytest.MonkeyPatch) -> None:
    known = _known_keys(monkeypatch)
    files = [*(ROOT / "worlds").glob("*.toml"), *(ROOT / "worlds").glob("*.json")]
    for path in sorted(files):
        if path.name not in {"foraging.json"}:  # a grid world's file
            load_world(path)
    assert {"size", "robots", "pose", "sonar", "boxes", "friction"} <= known
    assert _missing(known, REFERENCE / "world-file.md") == []


def test_the_formats_page_names_every_key_of_a_recording() -> None:
    world = World(load_world(ROOT / "worlds" / "search_and_rescue.toml"), seed=1)
    keys = set(scene_header(world)) | set(world.snapshot()) | {"commands", "phases"}
    assert _missing(keys, REFERENCE / "formats.md") == []
