"""The docs site's build hooks (``docs/_hooks.py``, not a package) as a module, for tests."""

from __future__ import annotations

import importlib.util
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def docs_hooks() -> types.ModuleType:
    """``docs/_hooks.py``, loaded."""
    spec = importlib.util.spec_from_file_location("mover_docs_hooks", ROOT / "docs" / "_hooks.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
