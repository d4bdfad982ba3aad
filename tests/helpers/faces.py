"""Checks of a package's public face that several test modules make: every class and function
``__all__`` lists has a docstring, and importing a module leaves the simulator out."""

from __future__ import annotations

import inspect
import subprocess
import sys
from types import ModuleType


def assert_documented(face: ModuleType) -> None:
    """Every class and function in ``face.__all__`` exists and has a docstring."""
    for name in face.__all__:
        obj = getattr(face, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            assert inspect.getdoc(obj), f"{face.__name__}.{name} has no docstring"


def loaded_roots(modules: str, roots: tuple[str, ...]) -> str:
    """The sorted list of the modules under ``roots`` that a fresh interpreter loads when it
    imports ``modules`` (a comma list, as an ``import`` statement takes it), as it prints it."""
    code = f"import sys, {modules}; print(sorted(m for m in sys.modules if m.split('.')[0] in "
    code += f"{roots!r}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.strip()
