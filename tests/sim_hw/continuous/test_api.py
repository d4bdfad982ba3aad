"""The public faces: sim_hw's ``__all__``, and the HAL the backends satisfy."""

from __future__ import annotations

import inspect

import pytest

import robots.hal as hal
import sim_hw
from sim_hw import World, WorldServer, WorldSpec, in_process
from tests.helpers.faces import assert_documented, loaded_roots

pytestmark = pytest.mark.processes


def test_all_names_exist_and_are_documented() -> None:
    assert_documented(sim_hw)
    public = {
        n for n in dir(sim_hw) if not n.startswith("_") and not inspect.ismodule(getattr(sim_hw, n))
    }
    assert public <= set(sim_hw.__all__) | {"annotations"}


def test_hal_imports_neither_pymunk_nor_sim_hw() -> None:
    assert loaded_roots("robots.hal", ("pymunk", "sim_hw")) == "[]"


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
    await server.door.aclose()


async def test_devices_can_be_left_out() -> None:
    server = WorldServer(World(WorldSpec()), expect=1)
    hw = await in_process(server, "r", {"sonar": False, "camera": False, "radio": False})
    assert (hw.sonar, hw.camera, hw.radio) == (None, None, None)
    await server.door.aclose()


def test_a_robot_s_backend_loads_no_world() -> None:
    """A robot process joins a world process: its backend needs neither pymunk nor the world,
    nor numpy (the stigmergic kinds' backends, which do, are a module of their own)."""
    assert loaded_roots("sim_hw.continuous._backend", ("pymunk", "matplotlib", "numpy")) == "[]"
