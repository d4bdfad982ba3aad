"""A robot process loads only what it uses: ``import mover`` (its command line and test helpers
too) brings in no numpy, and the wire imports numpy only once an array arrives. Each check runs
in a fresh interpreter, since this one has numpy loaded already. (That a robot's backend loads
neither pymunk nor the world: tests/sim_hw/continuous/test_api.py.)"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from mover._wire import pack
from tests.helpers.faces import loaded_roots

pytestmark = pytest.mark.processes


def test_mover_loads_no_numpy() -> None:
    assert loaded_roots("mover, mover.cli, mover.testing", ("numpy",)) == "[]"


def test_the_wire_imports_numpy_only_when_an_array_arrives() -> None:
    array = pack({"a": np.arange(6, dtype="<i4").reshape(2, 3)})
    code = f"""
import sys
from mover._wire import pack, unpack
plain = unpack(pack({{"x": [1, 2.5, b"b", "s", None], "set": {{3, 1}}}}))
assert plain == {{"x": [1, 2.5, b"b", "s", None], "set": [1, 3]}}, plain
print("numpy" in sys.modules)
print(unpack(bytes.fromhex({array.hex()!r}))["a"].tolist(), "numpy" in sys.modules)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.splitlines() == ["False", "[[0, 1, 2], [3, 4, 5]] True"]
