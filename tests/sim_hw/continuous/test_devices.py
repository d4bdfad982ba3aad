"""Each sensor against a case worked out by hand."""

from __future__ import annotations

import math

import pytest

from robots.hal import Hardware
from sim_hw import BoxSpec, MarkerSpec, ObstacleSpec, RobotSpec, SonarSpec, World, WorldSpec

from .conftest import start

R = 0.15  # robot radius


def test_sonar_ranges_from_the_rim() -> None:
    spec = WorldSpec(
        size=(10.0, 8.0), obstacles=(ObstacleSpec("circle", center=(8.5, 2.0), radius=0.5),)
    )
    world = World(spec)
    sonar = SonarSpec(rays=4, max_range=3.0)
    readings = world.add_robot("r", RobotSpec(pose=(8.5, 4.0, 0.0), sonar=sonar))
    assert readings["sonar"] is not None
    east, north, west, south = readings["sonar"]
    assert east == pytest.approx(10.0 - 8.5 - R, abs=1e-6)  # wall face at x = 10
    assert north == 3.0  # 3.85 m away: beyond range
    assert west == 3.0
    assert south == pytest.approx(4.0 - 2.0 - 0.5 - R, abs=1e-6)


def test_sonar_turns_with_the_robot() -> None:
    world = World(WorldSpec(size=(10.0, 8.0)))
    sonar = SonarSpec(rays=4, max_range=3.0)
    readings = world.add_robot("r", RobotSpec(pose=(5.0, 1.0, math.pi / 2), sonar=sonar))
    # facing north: ray 2 (behind) points south, 1 m from the wall at y = 0
    assert readings["sonar"] is not None
    assert readings["sonar"][2] == pytest.approx(1.0 - R, abs=1e-6)


def test_bumper_names_the_side_that_touches() -> None:
    world = World(WorldSpec(size=(10.0, 8.0)))
    world.add_robot("right", RobotSpec(pose=(5.0, R - 0.001, 0.0)))  # wall y=0 on its right
    world.add_robot("front", RobotSpec(pose=(3.0, 4.0, 0.0)))
    world.add_robot("free", RobotSpec(pose=(3.0, 6.0, 0.0)))
    world.robots  # noqa: B018
    world.add_robot("left", RobotSpec(pose=(3.0 + 2 * R - 0.002, 4.0, math.pi / 2)))
    world.step()
    assert world.readings("right")["bump"] == "right"
    assert world.readings("front")["bump"] == "front"  # touches "left" ahead of it
    assert world.readings("left")["bump"] == "left"  # "front" is on its left (it faces north)
    assert world.readings("free")["bump"] is None


def test_camera_reports_range_bearing_and_status() -> None:
    spec = WorldSpec(
        size=(10.0, 8.0),
        boxes=(BoxSpec("box", center=(2.0, 2.0), size=(0.4, 0.4), mass=20.0, status="red"),),
        markers=(
            MarkerSpec("beacon", "b", center=(1.0, 3.0)),  # 90° left: outside a 120° view
            MarkerSpec("target", "t", center=(3.5, 1.0)),  # dead ahead, 2.5 m
            MarkerSpec("resource", "far", center=(5.0, 1.0), status="3"),  # 4 m: out of range
        ),
    )
    world = World(spec)
    world.add_robot("other", RobotSpec(pose=(1.5, 0.5, 0.0), led="busy"))
    readings = world.add_robot("me", RobotSpec(pose=(1.0, 1.0, 0.0)))
    assert readings["cam"] is not None
    seen = {s[1]: s for s in readings["cam"]}
    assert set(seen) == {"box", "t", "other"}
    assert seen["box"][:3] == ["box", "box", "red"]
    assert seen["box"][3] == pytest.approx(math.sqrt(2), abs=1e-9)
    assert seen["box"][4] == pytest.approx(math.pi / 4, abs=1e-9)
    assert seen["t"][3:] == pytest.approx([2.5, 0.0], abs=1e-9)
    assert seen["other"][:3] == ["robot", "other", "busy"]
    assert seen["other"][4] == pytest.approx(-math.pi / 4, abs=1e-9)
    assert [s[1] for s in readings["cam"]] == ["other", "box", "t"]  # nearest first


@pytest.mark.parametrize("occlusion", [True, False])
def test_camera_does_not_see_through_walls(occlusion: bool) -> None:
    from sim_hw import CameraSpec

    spec = WorldSpec(
        size=(10.0, 8.0),
        obstacles=(ObstacleSpec("box", center=(2.0, 1.0), size=(0.2, 0.2)),),
        markers=(MarkerSpec("target", "t", center=(3.0, 1.0)),),
    )
    camera = CameraSpec(occlusion=occlusion)
    readings = World(spec).add_robot("me", RobotSpec(pose=(1.0, 1.0, 0.0), camera=camera))
    assert bool(readings["cam"]) is not occlusion


async def test_odometry_without_noise_follows_the_wheels() -> None:
    world = World(WorldSpec(size=(10.0, 8.0)))
    server, hws = await start(world, {"r": {"pose": [1.0, 1.0, 0.0]}})
    hw = hws["r"]
    hw.drive.set_velocity(0.3, 0.0)
    await hw.clock.sleep(2.0)
    x, y, th = hw.odometry.pose()
    # 120 steps; the first moves nothing (see below), the second at the force-limited
    # 70 N / 5 kg · 1/60 s = 0.2333 m/s, the other 118 at 0.3 m/s
    assert x == pytest.approx(1.0 + (70 / 5 / 60 + 118 * 0.3) / 60, abs=1e-9)
    assert (y, th) == pytest.approx((1.0, 0.0), abs=1e-6)
    hw.drive.set_velocity(0.0, math.pi / 2)
    await hw.clock.sleep(1.0)
    # chipmunk moves bodies before it solves joints: a command acts one physics step late
    assert hw.odometry.pose()[2] == pytest.approx(math.pi / 2 * (1 - 1 / 60), abs=1e-6)
    assert hw.odometry.pose() == pytest.approx(world.pose("r"), abs=1e-3)  # midpoint rule
    await server.door.aclose()


async def test_odometry_noise_drifts_reproducibly() -> None:
    async def run() -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        world = World(WorldSpec(size=(10.0, 8.0)), seed=7)
        spec = {"pose": [1.0, 1.0, 0.0], "odometry": {"trans_noise": 0.1, "drift": 0.05}}
        server, hws = await start(world, {"r": spec})
        hws["r"].drive.set_velocity(0.3, 0.0)
        await hws["r"].clock.sleep(5.0)
        await server.door.aclose()
        return hws["r"].odometry.pose(), world.pose("r") if "r" in world.robots else (0, 0, 0)

    (odom, _), (again, _) = await run(), await run()
    assert odom == again
    assert odom[0] == pytest.approx(2.5, abs=0.5)  # σ ≈ 0.1 m/m · 1.5 m per-tick errors
    assert odom != pytest.approx((2.5, 1.0, 0.0), abs=1e-4)


async def test_floor_cells_and_led() -> None:
    spec = WorldSpec(size=(10.0, 8.0), cell=0.5, floor=((2, 2, 7, "green"),))
    world = World(spec)
    server, hws = await start(
        world, {"a": {"pose": [1.2, 1.2, 0.0]}, "b": {"pose": [2.2, 1.2, 180.0]}}
    )  # degrees
    a, b = hws["a"], hws["b"]
    assert a.floor is not None and b.floor is not None and a.led is not None  # every robot has
    assert b.camera is not None and a.radio is not None  # these devices by default
    assert a.floor.read().value == 7
    assert a.floor.read().colour == "green"
    b.floor.write(3, "red")
    assert b.floor.read().value == 3  # a pending write reads back at once
    a.led.show("found")
    await asyncio_tick(a, b)
    assert world.floor.read(2.2, 1.2) == (3, "red")
    assert b.floor.read().colour == "red"
    assert [(s.id, s.status) for s in b.camera.sightings()] == [("a", "found")]
    assert a.radio.position() == pytest.approx(world.pose("a"))
    await server.door.aclose()


async def asyncio_tick(*hws: Hardware) -> None:
    import asyncio

    await asyncio.gather(*(hw.clock.tick() for hw in hws))
