"""Warnings for mover's deprecated names, in one place: each name goes in the next release.

A name still used inside this repository is in ``UNSWEPT``: it is served silently (pytest runs
with warnings as errors) until the repository's own uses are renamed; then it leaves the set
and warns like the others.
"""

from __future__ import annotations

import warnings

UNSWEPT: frozenset[str] = frozenset(
    {"mover.Team", "mover.TaskTeam", "mover.free_port", "Node.team"}
)


def warn(name: str, advice: str) -> None:
    """Warn (DeprecationWarning, at the caller's caller) that ``name`` is deprecated."""
    if name not in UNSWEPT:
        message = f"{name} is deprecated and goes in the next release: {advice}"
        warnings.warn(message, DeprecationWarning, stacklevel=3)
