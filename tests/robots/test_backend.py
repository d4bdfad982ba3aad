"""Hardware backends: the installed ones satisfy ``robots.backend.HardwareBackend``, options are
checked and passed through, and each offers the procedures of its own hardware."""

from __future__ import annotations

import asyncio
from importlib.metadata import EntryPoint
from typing import Any

import numpy as np
import pytest

import robots.process as process
import sim_hw.continuous._backend as continuous_backend
import sim_hw.grid._backend as grid_backend
from mover.cli import UsageError
from robots import Robot
from robots.backend import HardwareBackend, check_options
from robots.cli import backend_options
from robots.grid_hal import GridHardware
from robots.procedures import body_procedures, grid_procedures
from sim_hw import World, WorldServer, WorldSpec, in_process
from sim_hw.grid import Grid, GridServer, GridWorld
from sim_hw.grid import in_process as grid_in_process


def test_the_installed_backends_are_backends() -> None:
    found = {name: ep.load() for name, ep in process.hardware_backends().items()}
    assert found["sim"] is continuous_backend.BACKEND
    assert found["grid"] is grid_backend.BACKEND
    for backend in found.values():
        assert isinstance(backend, HardwareBackend)
    assert found["sim"].options == {"world", "call_timeout"}
    assert found["grid"].options == {"world", "call_timeout", "idle_period"}


def test_an_unknown_option_names_the_backend_s_options() -> None:
    with pytest.raises(ValueError, match=r"^hardware backend 'grid' takes no option 'wrld' "):
        process.load_backend("grid", {"wrld": "gridworld"})
    with pytest.raises(ValueError, match=r"\(its options: call_timeout, idle_period, world\)$"):
        check_options("grid", grid_backend.BACKEND, {"wrld": 1, "idle_period": 0.1})
    assert process.load_backend("sim", {"world": "w", "call_timeout": 5}) is not None


def test_a_workstation_has_no_backend_and_takes_no_options() -> None:
    assert process.load_backend("none") is None
    with pytest.raises(ValueError, match="takes no options"):
        process.load_backend("none", {"world": "w"})


def test_an_entry_point_that_is_no_backend_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    old = EntryPoint("old", "sim_hw.continuous:remote", "mover.hardware")  # a bare factory
    monkeypatch.setattr(process, "hardware_backends", lambda: {"old": old})
    with pytest.raises(ValueError, match=r"'old' \(sim_hw.continuous:remote\) is not a Hard"):
        process.load_backend("old")
    with pytest.raises(ValueError, match=r"no hardware backend 'warp' \(installed: old;"):
        process.load_backend("warp")


@pytest.mark.parametrize(
    ("backend", "target", "options", "expected"),
    [
        (
            continuous_backend,
            "remote",
            {},
            {"spec": None, "world": "world", "call_timeout": 30.0},
        ),
        (
            continuous_backend,
            "remote",
            {"world": "arena", "call_timeout": 5},
            {"spec": None, "world": "arena", "call_timeout": 5.0},
        ),
        (
            grid_backend,
            "connect",
            {},
            {"spec": {}, "world": "gridworld", "call_timeout": 30.0, "idle_period": 0.01},
        ),
        (
            grid_backend,
            "connect",
            {"world": "maze", "idle_period": 0},
            {"spec": {}, "world": "maze", "call_timeout": 30.0, "idle_period": 0.0},
        ),
    ],
)
async def test_connect_passes_the_options_on(
    monkeypatch: pytest.MonkeyPatch,
    backend: Any,
    target: str,
    options: dict[str, Any],
    expected: dict[str, Any],
) -> None:
    calls: list[tuple[Any, ...]] = []

    async def fake(node: Any, robot_id: str, spec: Any, **kwargs: Any) -> str:
        calls.append((node, robot_id, {"spec": spec, **kwargs}))
        return "hw"

    monkeypatch.setattr(backend, target, fake)
    assert await backend.BACKEND.connect("node", "r1", {}, **options) == "hw"
    assert calls == [("node", "r1", expected)]


def test_backend_options_come_from_world_and_option() -> None:
    items = ["call_timeout=60", "idle_period=0.5", "name=maze-7", "flag=true", 'q="3"', "e="]
    assert backend_options("arena", items) == {
        "call_timeout": 60,
        "idle_period": 0.5,
        "name": "maze-7",  # not JSON: the string itself
        "flag": True,
        "q": "3",
        "e": "",
        "world": "arena",
    }
    assert backend_options(None, []) == {}
    for bad, message in [
        (["timeout"], "expected KEY=VALUE"),
        (["=3"], "expected KEY=VALUE"),
        (["a=1", "a=2"], "given twice"),
    ]:
        with pytest.raises(UsageError, match=message):
            backend_options(None, bad)
    with pytest.raises(UsageError, match="the world is given twice"):
        backend_options("w", ["world=v"])


async def test_body_procedures_sense_the_devices_there_are() -> None:
    server = WorldServer(World(WorldSpec()), expect=2)
    full, bare = await asyncio.gather(
        in_process(server, "full"), in_process(server, "bare", {"sonar": False, "camera": False})
    )
    assert Robot("full", full).hw is full  # a bare Robot is Robot[Hardware]
    procs = body_procedures(full)
    assert set(procs) == {"robot.pose", "robot.stop", "robot.sense"}
    assert procs["robot.pose"]() == list(full.odometry.pose())
    seen = procs["robot.sense"]()
    assert set(seen) == {"time", "pose", "sonar", "bumper", "camera"}
    assert len(seen["sonar"]) == len(full.sonar.angles)  # type: ignore[union-attr]
    assert isinstance(seen["camera"], list)
    seen = body_procedures(bare)["robot.sense"]()
    assert (seen["sonar"], seen["camera"]) == (None, None)
    procs["robot.stop"]()
    await server.door.aclose()


async def test_grid_procedures_sense_the_grid() -> None:
    grid = Grid(np.array([[1, 1, 1, 1], [1, 0, 0, 1], [1, 1, 1, 1]]))
    server = GridServer(GridWorld(grid, (1, 1)), expect=1)
    hw = await grid_in_process(server, "a", {"start": [1, 1]})
    robot: Robot[GridHardware] = Robot("a", hw)
    procs = grid_procedures(robot.hw)
    assert set(procs) == {"robot.pose", "robot.stop", "robot.sense"}
    assert procs["robot.pose"]() == [0.0, 0.0, 0.0]
    seen = procs["robot.sense"]()
    assert set(seen) == {"round", "pose", "here", "around"}
    assert seen["round"] == 0 and seen["pose"] == [0.0, 0.0, 0.0]
    assert seen["here"] == {
        "value": hw.senses.here().value,
        "colour": 0,
        "resource": 0,
        "base": True,  # the world's base is the robot's start cell
        "pheromone": 0.0,
    }
    assert [n["direction"] for n in seen["around"]] == [0, 1, 2, 3]
    assert [n["state"] for n in seen["around"]] == [1, 0, 1, 1]  # only east is free
    procs["robot.stop"]()
