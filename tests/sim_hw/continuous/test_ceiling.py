"""The ceiling layer: what eye-bots see of foot-bots, and what foot-bots hear and see of them."""

import math

import numpy as np
import pytest

from robots.stigmergic import (
    EyeBot,
    FootBotSeen,
    Goal,
    Reading,
    direction_index,
    read_leds,
    show_leds,
)
from sim_hw.continuous import Ceiling, EyeBotSpec, RobotSpec, World, WorldSpec


def _world(*robots: tuple[str, tuple[float, float, float], str]) -> World:
    world = World(WorldSpec(size=(10.0, 10.0)))
    for rid, pose, led in robots:
        world.add_robot(rid, RobotSpec(pose=pose, radius=0.085, sonar=None, camera=None, led=led))
    return world


EYES = [EyeBotSpec("e1", (2.0, 2.0), heading=math.pi / 2), EyeBotSpec("e2", (4.0, 2.0))]


def test_a_foot_bot_under_an_eye_bot_hears_only_that_eye_bot() -> None:
    world = _world(
        ("f1", (2.3, 2.1, 0.0), ""), ("f2", (3.0, 2.0, 0.0), ""), ("f3", (3.8, 1.9, 1.0), "")
    )
    ceiling = Ceiling(world, EYES)
    ceiling.sense()
    above = ceiling.above("f1")
    assert above is not None and above[0] == "e1"
    assert above[1] == pytest.approx(math.pi / 2)  # θ0 = north, it faces east
    assert ceiling.above("f2") is None  # between the cones
    eye, theta0 = ceiling.above("f3") or ("", 0.0)
    assert eye == "e2" and theta0 == pytest.approx(-1.0)
    assert dict(ceiling.under()) == {"f1": "e1", "f2": None, "f3": "e2"}


def test_an_eye_bot_sees_only_the_foot_bots_in_its_view_with_their_leds() -> None:
    going = show_leds(False, Goal.TARGET)
    world = _world(
        ("f1", (2.5, 2.0, 0.0), going),  # 0.5 m east of e1, heading east
        ("f2", (2.0, 2.9, 0.0), show_leds(True, None)),  # 0.9 m north, avoiding
        ("f3", (2.0, 3.2, 0.0), going),  # 1.2 m: out of view
    )
    ceiling = Ceiling(world, EYES)
    ceiling.sense()
    seen = {b.robot: b for b in ceiling.camera("e1")}
    assert set(seen) == {"f1", "f2"}
    f1 = seen["f1"]
    # e1's frame has x along θ0 = north: east is -y there
    assert f1.beacon == pytest.approx((0.0, -0.5), abs=1e-9)
    assert f1.front is not None and f1.front[1] < f1.beacon[1]
    assert read_leds(f1.led) == (False, Goal.TARGET)
    assert seen["f2"].front is None and read_leds(seen["f2"].led) == (True, None)


def test_an_eye_bot_reads_theta_f_within_its_resolution_and_learns_from_it() -> None:
    for k in range(12):
        heading = k * math.pi / 6 + 0.2
        world = _world(("f", (4.2, 2.1, heading), show_leds(False, Goal.TARGET)))
        ceiling = Ceiling(world, EYES)
        ceiling.sense()
        (below,) = ceiling.camera("e2")
        seen = FootBotSeen(beacon=below.beacon, front=below.front, goal=Goal.TARGET)
        came_from = seen.came_from()
        assert came_from is not None
        assert direction_index(came_from) == direction_index(heading + math.pi)
        eye = EyeBot(rng=np.random.default_rng(0), reading=Reading.ANY)  # the old reading
        eye.observe([seen])
        assert eye.to_source.best() == direction_index(heading + math.pi)
        eye = EyeBot(rng=np.random.default_rng(0))  # the default: approaching foot-bots only
        eye.observe([seen])
        learned = len(set(eye.to_source.prefs.tolist())) > 1
        assert learned == seen.coming_towards()
        if learned:
            assert eye.to_source.best() == direction_index(heading + math.pi)


def test_the_omnidirectional_camera_sees_eye_bots_within_range_nearest_first() -> None:
    world = _world(("f", (1.0, 2.0, math.pi / 2), ""))
    ceiling = Ceiling(world, [*EYES, EyeBotSpec("far", (9.0, 9.0))], omni_range=3.5)
    ceiling.sense()
    (d1, b1), (d2, b2) = ceiling.omni("f")
    assert d1 == pytest.approx(1.0) and b1 == pytest.approx(-math.pi / 2)  # e1 to its right
    assert d2 == pytest.approx(3.0) and b2 == pytest.approx(-math.pi / 2)


def test_eye_bots_are_not_in_the_physics() -> None:
    world = _world(("f", (2.0, 2.0, 0.0), ""))
    before = len(world.space.shapes)
    Ceiling(world, EYES)
    assert len(world.space.shapes) == before
    with pytest.raises(ValueError, match="unique"):
        Ceiling(world, [EYES[0], EYES[0]])
