"""Warnings for mover's deprecated names, in one place: each name goes in the next release.

Nothing in this repository uses a deprecated name (pytest runs with warnings as errors, so a
use would fail its test).
"""

from __future__ import annotations

import warnings


def warn(name: str, advice: str) -> None:
    """Warn (DeprecationWarning, at the caller's caller) that ``name`` is deprecated."""
    message = f"{name} is deprecated and goes in the next release: {advice}"
    warnings.warn(message, DeprecationWarning, stacklevel=3)
