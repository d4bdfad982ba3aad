"""``mover view`` and ``mover replay`` on an install without the view extra: one line that
names the extra, before a team or a file is asked for (the default install has no viewer)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import pytest

from mover._cli import main

ROOT = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize("verb", [["view"], ["replay", str(ROOT / "README.md")]])
def test_the_viewer_without_rerun_is_one_line(
    verb: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    real = importlib.util.find_spec

    def no_rerun(name: str, *rest: Any) -> Any:
        return None if name.startswith("rerun") else real(name, *rest)

    monkeypatch.setattr(importlib.util, "find_spec", no_rerun)
    monkeypatch.delenv("MOVER_TEAM", raising=False)
    assert main(verb) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert err == [f"mover {verb[0]}: the viewer needs rerun-sdk: pip install 'mover[view]'"]
