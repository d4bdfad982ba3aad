"""The public faces: sim_hw's ``__all__``, and the HAL the backends satisfy."""

from __future__ import annotations

import inspect
import subprocess
import sys

import pytest

import robots.hal as hal
import sim_hw
from sim_hw import World, WorldServer, WorldSpec, in_process

pytestmark = pytest.mark.processes


def test_all_names_exist_and_are_documented() -> None:
    for name in sim_hw.__all__:
        obj = getattr(sim_hw, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            assert inspect.getdoc(obj), f"sim_hw.{name} has no docstring"
    public = {
        n for n in dir(sim_hw) if not n.startswith("_") and not inspect.ismodule(getattr(sim_hw, n))
    }
    assert public <= set(sim_hw.__all__) | {"annotations"}


def test_hal_imports_neither_pymunk_nor_sim_hw() -> None:
    code = "import sys, robots.hal; print(sorted(m for m in sys.modules if m.split('.')[0] in "
    code += "('pymunk', 'sim_hw')))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


async def test_the_backend_satisfies_every_protocol() -> None:
    server = WorldServer(World(WorldSpec()), expect=1)
    hw = await in_process(server, "r")
    assert isinstance(hw, hal.Hardware)
    checks = {
        "clock": hal.Clock,
        "drive": hal.Drive,
        "odometry": hal.Odometry,
        "sonar": hal.Sonar,
        "bumper": hal.Bumper,
        "camera": hal.Camera,
        "led": hal.Led,
        "radio": hal.RadioLocator,
        "floor": hal.FloorCells,
        "push": hal.PushSense,
    }
    for field, protocol in checks.items():
        assert isinstance(getattr(hw, field), protocol), field
    await server.aclose()


async def test_devices_can_be_left_out() -> None:
    server = WorldServer(World(WorldSpec()), expect=1)
    hw = await in_process(server, "r", {"sonar": False, "camera": False, "radio": False})
    assert (hw.sonar, hw.camera, hw.radio) == (None, None, None)
    await server.aclose()
