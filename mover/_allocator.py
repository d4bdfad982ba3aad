"""glibc's allocator held to fixed thresholds, so that large payloads do not fault in fresh pages.

By default glibc moves its mmap threshold and its trim threshold with what a process frees: a
process that has both freed a large block and shrunk its heap can end up handing each large
payload fresh pages (mapped, faulted in and zeroed, then returned), a few hundred page faults a
1 MiB call. It happens after some sequences of calls and not others (docs/transport.md, "Large
calls and the allocator"). Fixed thresholds, set once before zenoh starts its threads, keep
blocks up to :data:`MMAP_THRESHOLD` in the heaps and free memory up to :data:`TRIM_THRESHOLD`
mapped: a large call then costs what it costs the first time, whatever came before.

``MOVER_ALLOCATOR=default`` leaves glibc as it is (``held``, or unset: the thresholds held; any
other value is logged and held), as does any ``MALLOC_*_`` tunable in the environment (the
user's choice wins); other C libraries are left alone.
"""

from __future__ import annotations

import logging
import os
import sys

log = logging.getLogger(__name__)

M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
MMAP_THRESHOLD = 8 << 20
"""Blocks up to this size come from the heaps (mover's largest payload is 4 MiB by default)."""
TRIM_THRESHOLD = 32 << 20
"""Free memory at a heap's top kept mapped, up to this size."""
USERS_TUNABLES = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_")

_held: bool | None = None


def hold_thresholds() -> bool:
    """Fix glibc's mmap and trim thresholds for this process, once (see the module); whether
    they are held."""
    global _held
    if _held is None:
        _held = _hold()
    return _held


def _hold() -> bool:
    choice = os.environ.get("MOVER_ALLOCATOR", "").strip().lower()
    if choice == "default":
        return False
    if choice not in ("", "held"):
        log.warning("MOVER_ALLOCATOR=%r is not 'default' or 'held': holding the thresholds", choice)
    if not sys.platform.startswith("linux") or any(k in os.environ for k in USERS_TUNABLES):
        return False
    import ctypes  # (only here: a process that never opens a node does not load it)

    try:
        libc = ctypes.CDLL(None)
        if not hasattr(libc, "gnu_get_libc_version"):  # not glibc
            return False
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    held = bool(
        mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) and mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    )
    if not held:
        log.debug("glibc refused the allocator thresholds; left as they were")
    return held
