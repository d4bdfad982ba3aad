"""Tests of the network lab and of teams across its hosts."""

from __future__ import annotations

import pytest

from mover.testing import netlab_unavailable

LAB = [
    pytest.mark.processes,
    pytest.mark.netns,
    pytest.mark.skipif(
        (reason := netlab_unavailable()) is not None, reason=f"no lab of hosts: {reason}"
    ),
]
"""The marks of a module whose tests need the lab of hosts (network namespaces): ``pytestmark =
LAB``. Skipped, saying why, where the lab cannot be made."""
