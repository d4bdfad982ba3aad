"""The documentation site builds in strict mode, and its docstring check catches what it should.

The build is mkdocs's own, in this process (no server, no network): a broken link, a reference
mkdocstrings cannot resolve, a public name without a docstring (docs/_hooks.py) or a verb whose
entry point does not load fails it, as `make docs` does.
"""

from __future__ import annotations

import logging
import sys
import types
from importlib.metadata import entry_points
from pathlib import Path

import pytest
from mkdocs.commands.build import build
from mkdocs.config import load_config
from mkdocs.exceptions import Abort, PluginError

from tests.helpers.docs_hooks import docs_hooks

# griffe (mkdocstrings' reader of the sources) asks git where each package's repository is
pytestmark = pytest.mark.processes

ROOT = Path(__file__).resolve().parents[2]


def test_the_site_builds_in_strict_mode(tmp_path: Path) -> None:
    config = load_config(str(ROOT / "mkdocs.yml"), site_dir=str(tmp_path / "site"), strict=True)
    try:
        build(config)
    except (Abort, PluginError) as exc:
        pytest.fail(f"mkdocs build --strict failed: {exc}")
    finally:
        logging.getLogger("mkdocs").handlers.clear()  # mkdocs adds a counting handler per build
    cli = (tmp_path / "site" / "reference" / "cli" / "index.html").read_text()
    verbs = {ep.name for ep in entry_points(group="mover.commands")}
    assert {"up", "run", "drive", "topics", "call", "echo"} <= verbs
    assert [v for v in sorted(verbs) if f'id="mover-{v}"' not in cli] == []  # a section each
    mover = (tmp_path / "site" / "reference" / "mover" / "index.html").read_text()
    assert "distributed_or" in mover and "Run ``operation`` on every member" not in mover


def test_a_name_without_a_docstring_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    module = types.ModuleType("fake_public", "A module with one undocumented name.")

    class Documented:
        """It has one."""

        def method(self) -> None:
            pass

    def bare() -> None:
        pass

    module.Documented = Documented  # type: ignore[attr-defined]
    module.bare = bare  # type: ignore[attr-defined]
    module.__all__ = ["Documented", "bare"]  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "fake_public", module)
    assert docs_hooks().undocumented(["fake_public"]) == [
        "fake_public.Documented.method",
        "fake_public.bare",
    ]
