"""A world with eye-bots on its ceiling behind the lock-step door: the world file's sections,
joins of the two kinds, the IrRB instruction as an eye-bot's command heard by the foot-bots
under it after the tick, the downward camera, the area sensor, and runs that repeat."""

from __future__ import annotations

import asyncio
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from robots.stigmergic import (
    EyeBot,
    FootBot,
    Goal,
    Instruction,
    eyebot_loop,
    footbot_loop,
    read_leds,
    show_leds,
)
from sim_hw.continuous import (
    World,
    WorldFileError,
    WorldServer,
    eyebot_in_process,
    footbot_in_process,
    in_process,
    load_world,
    parse_world,
)

ROOT = Path(__file__).resolve().parents[3]


def _file(**extra: Any) -> dict[str, Any]:
    """Two eye-bots 2 m apart (e1's θ0 north), three foot-bots, the source and target areas."""
    data: dict[str, Any] = {
        "world": {"size": [6.0, 4.0]},
        "robot": {"radius": 0.085, "camera": False, "sonar": {"rays": 8, "max_range": 0.3}},
        "ceiling": {"omni_range": 2.5},
        "eyebots": [
            {"id": "e1", "center": [2.0, 2.0], "heading": 90, "view": 0.9},
            {"id": "e2", "center": [4.0, 2.0], "view": 0.8, "cone": 0.4},
        ],
        "areas": [
            {"id": "source", "center": [4.0, 2.0], "radius": 0.5},
            {"id": "target", "center": [1.0, 1.0]},
        ],
        "robots": [
            {"id": "f1", "pose": [2.2, 2.1, 0.0], "led": show_leds(False, Goal.TARGET)},
            {"id": "f2", "pose": [3.0, 2.0, 0.0]},  # between the cones
            {"id": "f3", "pose": [3.9, 2.0, 90.0]},  # under e2, in the source area
        ],
    }
    data.update(extra)
    return data


def test_the_world_file_hangs_eye_bots_and_marks_the_areas() -> None:
    spec = parse_world(_file(), "t.toml")
    e1, e2 = spec.eyebots
    assert (e1.id, e1.center, e1.heading, e1.view, e1.cone) == (
        "e1",
        (2.0, 2.0),
        math.pi / 2,
        0.9,
        0.5,
    )
    assert (e2.view, e2.cone) == (0.8, 0.4)
    assert [(a.id, a.radius) for a in spec.areas] == [("source", 0.5), ("target", 1.0)]
    assert spec.omni_range == 2.5
    shipped = load_world(ROOT / "worlds" / "stigmergic_navigation.toml")
    assert len(shipped.eyebots) == 11 and len(shipped.robots) == 5
    assert {a.id for a in shipped.areas} == {"source", "target"}


@pytest.mark.parametrize(
    ("change", "field", "problem"),
    [
        (
            {"eyebots": [{"id": "e1", "center": [1, 1], "colour": "red"}]},
            "eyebots[0].colour",
            "unknown",
        ),
        ({"eyebots": [{"id": "e1", "center": [1, 1]}] * 2}, "eyebots[1].id", "already used"),
        ({"eyebots": [{"id": "f1", "center": [1, 1]}]}, "eyebots[0].id", "already used"),
        ({"eyebots": [{"id": "no way", "center": [1, 1]}]}, "eyebots[0].id", ""),
        ({"eyebots": [{"id": "e1", "center": [1, 1], "view": 0}]}, "eyebots[0].view", "> 0"),
        ({"areas": [{"id": "a"}]}, "areas[0].center", "required"),
        ({"ceiling": {"omni": 3}}, "ceiling.omni", "unknown"),
    ],
)
def test_a_wrong_ceiling_in_a_world_file_is_named(
    change: dict[str, Any], field: str, problem: str
) -> None:
    with pytest.raises(WorldFileError) as err:
        parse_world(_file(**change), "t.toml")
    assert err.value.field == field and problem in err.value.problem


async def _server(expect: int = 0) -> WorldServer:
    return WorldServer(World(parse_world(_file(), "t.toml"), seed=1), expect=expect)


async def test_each_kind_joins_as_itself_and_a_wrong_kind_is_refused() -> None:
    server = await _server(expect=2)
    try:
        with pytest.raises(ValueError, match="no eye-bot 'f1'"):
            await eyebot_in_process(server, "f1")
        with pytest.raises(ValueError, match="is an eye-bot of this world"):
            await footbot_in_process(server, "e1")
        with pytest.raises(ValueError, match="is an eye-bot"):
            await in_process(server, "e2", {"radius": 0.1})  # a body for an eye-bot
        eye, foot = await asyncio.gather(
            eyebot_in_process(server, "e1"), footbot_in_process(server, "f1")
        )
        assert (eye.camera.view, eye.irrb.cone) == (0.9, 0.5)
        assert foot.omni.max_range == 2.5 and foot.sonar.max_range == 0.3
        assert "e1" not in server.world.robots  # an eye-bot is no body of the physics
    finally:
        await server.door.aclose()


async def test_an_instruction_is_heard_after_the_tick_by_the_foot_bots_under_that_eye_bot() -> None:
    server = await _server(expect=5)
    try:
        (e1, e2), (f1, f2, f3) = await asyncio.gather(
            asyncio.gather(eyebot_in_process(server, "e1"), eyebot_in_process(server, "e2")),
            asyncio.gather(*(footbot_in_process(server, f) for f in ("f1", "f2", "f3"))),
        )
        assert f1.up.above() is None  # e1 has sent nothing yet
        e1.irrb.send(Instruction(to_source=0.5, to_target=-1.0))
        await asyncio.gather(*(hw.clock.tick() for hw in (e1, e2, f1, f2, f3)))
        heard = f1.up.above()
        assert heard is not None
        assert (heard.eyebot, heard.to_source, heard.to_target) == ("e1", 0.5, -1.0)
        assert heard.reference == pytest.approx(math.pi / 2)  # e1's θ0 north; f1 faces east
        assert f2.up.above() is None  # between the cones
        assert f3.up.above() is None  # under e2, which sent nothing
        # the omni camera: both eye-bots from f2, nearest first (e2 is 1 m east, e1 1 m west)
        (d1, b1), (d2, b2) = f2.omni.eyebots()
        assert d1 == pytest.approx(1.0) and d2 == pytest.approx(1.0)
        assert sorted([abs(b1), abs(b2)]) == [pytest.approx(0.0), pytest.approx(math.pi)]
        # the area sensor
        assert f3.area.area() is Goal.SOURCE and f1.area.area() is None
        # the downward camera: f1 0.2 m east and 0.1 north of e1, in e1's frame (x north)
        (spot,) = e1.camera.below()
        assert spot.beacon == pytest.approx((0.1, -0.2))
        assert read_leds(spot.led) == (False, Goal.TARGET) and spot.front is not None
        assert spot.front[1] < spot.beacon[1]  # it faces east: -y in e1's frame
        (spot3,) = e2.camera.below()
        assert spot3.front is None  # f3 shows no front LED
    finally:
        await server.door.aclose()


async def _run(seed: int, duration: float = 40.0) -> tuple[list[Any], list[Any]]:
    """The shipped arena's eye-bots and foot-bots in process for ``duration`` s."""
    spec = load_world(ROOT / "worlds" / "stigmergic_navigation.toml")
    eyes, feet = [e.id for e in spec.eyebots], sorted(spec.robots)
    server = WorldServer(World(spec, seed=seed), expect=len(eyes) + len(feet))
    eye_hws, foot_hws = await asyncio.gather(
        asyncio.gather(*(eyebot_in_process(server, e) for e in eyes)),
        asyncio.gather(*(footbot_in_process(server, f) for f in feet)),
    )
    rng = np.random.SeedSequence(seed).spawn(len(eyes) + len(feet))
    until = eye_hws[0].clock.now() + duration
    eyes_done, feet_done = await asyncio.gather(
        asyncio.gather(
            *(
                eyebot_loop(hw, EyeBot(np.random.default_rng(r)), 1.0, until)
                for hw, r in zip(eye_hws, rng, strict=False)
            )
        ),
        asyncio.gather(
            *(
                footbot_loop(hw, FootBot(np.random.default_rng(r)), until)
                for hw, r in zip(foot_hws, rng[len(eyes) :], strict=True)
            )
        ),
    )
    done = [*eyes_done, *feet_done]
    poses = [server.world.pose(f) for f in feet]
    await server.door.aclose()
    return list(done), poses


async def test_a_run_of_both_kinds_repeats_with_the_same_seed() -> None:
    (a, pa), (b, pb) = await _run(3), await _run(3)
    assert a == b and pa == pb
    eyes = [r for r in a if isinstance(r, dict)]
    assert sum(r["seen"] for r in eyes) > 0  # the eye-bots saw foot-bots
    assert pa != [p for p in (await _run(4))[1]]  # another seed, another run
