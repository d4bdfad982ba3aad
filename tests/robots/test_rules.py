"""The library's decision rules on hand-made readings: no world, no network, no clock."""

from __future__ import annotations

import math
import random

import pytest

from robots.hal import BumperSide, Sighting
from robots.library import (
    Found,
    Path,
    Rect,
    Wander,
    align,
    detour,
    follow_command,
    kind_ahead,
    locate,
    moved,
    object_pose,
    pusher_command,
    station,
    stations,
    steer,
    steerer_command,
    teammate_ahead,
)

ANGLES = tuple(2 * math.pi * i / 8 for i in range(8))
CLEAR = (3.0,) * 8


def seen(kind: str, ident: str, rng: float, bearing: float) -> Sighting:
    return Sighting(kind, ident, "", rng, bearing)


# -- search and recognition (section 4.1) ----------------------------------------------------


def test_wander_turns_to_a_random_heading_then_drives() -> None:
    walk = Wander(random.Random(1))
    action, v, w = walk.step((0.0, 0.0, 0.0), None, 3.0)
    assert action == "drive"
    goal = walk.goal
    assert v == 0.0 and math.copysign(1, w) == math.copysign(1, goal)  # turns toward the goal
    action, v, w = walk.step((0.0, 0.0, goal), None, 3.0)
    assert (action, v) == ("drive", walk.speed) and abs(w) < 1e-9


def test_wander_is_seeded() -> None:
    goals = [Wander(random.Random(7)) for _ in range(2)]
    for g in goals:
        g.step((0.0, 0.0, 0.0), None, 3.0)
    assert goals[0].goal == goals[1].goal


def test_wander_slows_near_things_and_checks_what_it_bumps() -> None:
    walk = Wander(random.Random(2))
    walk.step((0.0, 0.0, 0.0), None, 3.0)
    pose = (0.0, 0.0, walk.goal)
    assert walk.step(pose, None, 0.1)[1] == walk.creep
    assert walk.step(pose, "front", 0.0)[0] == "check"


def test_wander_backs_off_a_rejected_object_then_heads_away() -> None:
    walk = Wander(random.Random(3))
    walk.step((0.0, 0.0, 0.0), None, 3.0)
    walk.rejected((1.0, 0.0, 0.0))  # a wall straight ahead, along +x
    action, v, _ = walk.step((1.0, 0.0, 0.0), "front", 0.0)
    assert action == "drive" and v < 0
    walk.step((1.0 - walk.backoff, 0.0, 0.0), None, 0.3)
    assert walk.mode == "turn"
    assert math.cos(walk.goal) < math.cos(math.pi - 1.2) + 1e-9  # within 1.2 rad of -x


def test_rect_is_a_region_and_splits_into_quadrants() -> None:
    arena = Rect(0.0, 0.0, 6.0, 4.0)
    assert arena((6.0, 0.0)) and arena((1.0, 2.0, 0.5)) and not arena((6.1, 2.0))
    sw, se, nw, ne = arena.split()
    assert (sw, ne) == (Rect(0.0, 0.0, 3.0, 2.0), Rect(3.0, 2.0, 6.0, 4.0))
    assert se.centre == (4.5, 1.0) and nw.centre == (1.5, 3.0)


def heading_off(
    walk: Wander, pose: tuple[float, float, float], target: tuple[float, float]
) -> float:
    return abs(
        math.remainder(walk.goal - math.atan2(target[1] - pose[1], target[0] - pose[0]), math.tau)
    )


def test_wander_outside_its_rect_turns_back_toward_the_centre() -> None:
    walk = Wander(random.Random(5), region=Rect(0.0, 0.0, 2.0, 2.0))
    walk.step((1.0, 1.0, 0.0), None, 3.0)
    walk.goal, walk.mode = 0.0, "drive"  # heading east, out through x = 2
    assert walk.step((1.9, 1.0, 0.0), None, 3.0) == ("drive", walk.speed, 0.0)  # still inside
    outside = (2.2, 1.0, 0.0)
    action, v, _ = walk.step(outside, None, 3.0)
    assert walk.mode == "turn" and (action, v) == ("drive", 0.0)  # it turns on the spot
    assert heading_off(walk, outside, (1.0, 1.0)) <= walk.reenter


def test_wander_started_outside_its_rect_heads_in() -> None:
    walk = Wander(random.Random(6), region=Rect(4.0, 4.0, 6.0, 6.0))
    walk.step((0.0, 0.0, 0.0), None, 3.0)
    assert heading_off(walk, (0.0, 0.0, 0.0), (5.0, 5.0)) <= walk.reenter


def test_wander_outside_a_predicate_heads_back_to_where_it_was_inside() -> None:
    walk = Wander(random.Random(7), region=lambda p: p[1] < 1.0)  # south of y = 1, no centre
    walk.step((0.0, 0.0, 0.0), None, 3.0)
    for x in (0.0, 0.5, 1.0):  # it held (0.5, 0.5) inside on average
        walk.step((x, 0.5 * x + 0.25, 0.0), None, 3.0)
    walk.goal, walk.mode = math.pi / 2, "drive"
    outside = (1.0, 1.5, math.pi / 2)
    walk.step(outside, None, 3.0)
    assert heading_off(walk, outside, (0.5, 0.5)) <= walk.reenter


def test_wander_backs_off_a_contact_outside_its_region_before_turning_back() -> None:
    walk = Wander(random.Random(8), region=Rect(0.0, 0.0, 2.0, 2.0))
    walk.step((1.0, 1.0, 0.0), None, 3.0)
    walk.rejected((2.3, 1.0, 0.0))
    action, v, _ = walk.step((2.3, 1.0, 0.0), None, 0.0)
    assert walk.mode == "back" and action == "drive" and v < 0


@pytest.mark.parametrize("side", ["left", "right"])
def test_wander_turns_away_from_a_side_contact(side: BumperSide) -> None:
    walk = Wander(random.Random(4))
    walk.step((0.0, 0.0, 0.0), None, 3.0)
    walk.step((0.0, 0.0, 0.0), side, 3.0)
    assert walk.mode == "turn"
    towards = math.sin(walk.goal) if side == "left" else -math.sin(walk.goal)
    assert towards < math.sin(1.2) + 1e-9  # never deeper into the side that was touched


def test_moved_ignores_walls_and_a_box_that_does_not_give() -> None:
    assert not moved(0.0)  # a wall, an immovable object
    assert not moved(1e-8)  # the 2-robot box under one robot's square push
    assert moved(0.03)  # a box that gives


def test_teammates_are_not_objects() -> None:
    assert teammate_ahead([seen("robot", "ernst", 0.32, 0.1)])
    assert not teammate_ahead([seen("robot", "ernst", 0.32, 1.5)])  # beside, not ahead
    assert not teammate_ahead([seen("box", "victim", 0.45, 0.0)])


def test_kind_ahead_and_locate_use_the_nearest_thing_in_front() -> None:
    sightings = [seen("immovable", "pillar", 0.5, 1.2), seen("box", "victim", 0.6, 0.2)]
    assert kind_ahead(sightings) == "box"
    ident, (x, y) = locate((1.0, 1.0, math.pi / 2), sightings, 0.15)
    assert ident == "victim"
    assert x == pytest.approx(1.0 - 0.6 * math.sin(0.2)) and y == pytest.approx(
        1.0 + 0.6 * math.cos(0.2)
    )
    nobody, point = locate((0.0, 0.0, 0.0), [], 0.15)
    assert nobody is None and point == pytest.approx((0.45, 0.0))


def test_found_crosses_the_wire_as_a_list() -> None:
    found = Found("victim", (4.5, 3.0), (3.9, 3.0, 0.1))
    wire = [list(x) if isinstance(x, tuple) else x for x in found]  # what msgpack gives back
    assert Found.load(wire) == found


# -- navigation (section 4.3 goto-object) ----------------------------------------------------


def test_steer_goes_straight_to_a_clear_target() -> None:
    v, w = steer((0.0, 0.0, 0.0), (2.0, 0.0), CLEAR, ANGLES)
    assert v == pytest.approx(0.4) and w == pytest.approx(0.0)


def test_steer_turns_away_from_an_obstacle_on_the_left_front() -> None:
    ranges = list(CLEAR)
    ranges[1] = 0.1  # something 45° to the left
    ranges[0] = 0.3
    v, w = steer((0.0, 0.0, 0.0), (2.0, 0.0), ranges, ANGLES)
    assert w < 0 and v < 0.4


def test_steer_turns_on_the_spot_for_a_target_behind() -> None:
    v, w = steer((0.0, 0.0, 0.0), (-2.0, 0.1), CLEAR, ANGLES)
    assert v == 0.0 and w > 0


def test_detour_goes_round_the_object_the_short_way() -> None:
    assert detour((0.0, 0.0), (0.0, 3.0), (2.0, 1.5), 0.5) == [(0.0, 3.0)]  # clear
    points = detour((3.0, 0.2), (-1.0, 0.0), (1.0, 0.0), 1.0)
    assert points[-1] == (-1.0, 0.0)
    assert all(math.dist(p, (1.0, 0.0)) >= 1.0 - 1e-9 for p in points)
    assert all(p[1] >= 0 for p in points[:-1])  # over the top: the start is slightly above


def test_station_stands_behind_and_to_the_left() -> None:
    x, y, h = station((4.0, 3.0), math.pi / 2, 0.4, 0.9)
    assert (x, y) == pytest.approx((3.6, 2.1)) and h == math.pi / 2


def test_follow_keeps_the_gap_and_looks_for_a_lost_leader() -> None:
    assert follow_command(1.7, 0.0)[0] == pytest.approx(0.35)
    assert follow_command(0.6, 0.0) == (0.0, 0.0)
    assert follow_command(None, 0.0) == (0.0, 0.8)
    assert follow_command(1.5, 0.3)[1] > 0


# -- manipulation (section 4.3 pusher / steerer) ---------------------------------------------


def test_path_progress_cross_track_and_heading() -> None:
    path = Path.relative((1.0, 1.0), [(2.0, 0.0), (2.0, 2.0)])
    assert path.length() == pytest.approx(4.0)
    assert path.heading() == 0.0
    s, e, h = path.locate((2.0, 1.3))
    assert (s, e) == pytest.approx((1.0, 0.3)) and h == 0.0
    s, e, h = path.locate((3.2, 2.0))
    assert (s, e, h) == pytest.approx((3.0, -0.2, math.pi / 2))
    assert path.locate((3.0, 3.5))[0] == pytest.approx(4.5)  # overshoot counts
    assert path.shifted((0.0, -0.4)).vertices()[0] == (1.0, 0.6)


def test_stations_put_the_finder_at_the_right_corner_as_pusher() -> None:
    roles = stations("moseley", ["elvis", "ernst", "moseley"], 1.2)
    assert _roles(roles) == {"moseley": "pusher", "elvis": "steerer", "ernst": "steerer"}
    assert _offsets(roles) == pytest.approx({"moseley": -0.42, "elvis": 0.0, "ernst": 0.42})
    pair = stations("a", ["a", "b"], 0.6)
    assert _roles(pair) == {"a": "pusher", "b": "steerer"}
    assert _offsets(pair) == pytest.approx({"a": -0.12, "b": 0.12})


def _roles(stationed: dict[str, tuple[str, float]]) -> dict[str, str]:
    return {name: role for name, (role, _) in stationed.items()}


def _offsets(stationed: dict[str, tuple[str, float]]) -> dict[str, float]:
    return {name: offset for name, (_, offset) in stationed.items()}


def test_object_pose_from_a_sighting() -> None:
    # a robot at the right rear corner sees the centre 45° to its left
    s = seen("box", "victim", math.hypot(0.4, 0.4), math.pi / 4)
    x, y, h = object_pose((0.0, 0.0, 0.1), s, math.pi / 4)
    assert (x, y) == pytest.approx(
        (
            0.4 * math.sqrt(2) * math.cos(math.pi / 4 + 0.1),
            0.4 * math.sqrt(2) * math.sin(math.pi / 4 + 0.1),
        )
    )
    assert h == pytest.approx(0.1)


def test_pusher_holds_its_speed_and_keeps_square() -> None:
    s = seen("box", "victim", 0.6, 0.75)
    v, w = pusher_command(s, 0.7)
    assert v == 0.3 and w > 0  # the object turned left in view: turn with it
    assert align(None, 0.7) == 0.0


@pytest.mark.parametrize(("lateral", "faster"), [(-0.4, True), (0.4, False)])
def test_steerer_turns_the_object_back_to_the_path(lateral: float, faster: bool) -> None:
    path = Path.relative((0.0, 0.0), [(3.0, 0.0)])
    box = (1.0, -0.2, 0.0)  # right of the path, square: it must turn left
    v, _ = steerer_command(path, box, lateral, None, 0.0)
    assert (v > 0.3) is faster and abs(v - 0.3) <= 0.2 + 1e-9
    box = (1.0, 0.0, 0.3)  # on the path but turned left: it must turn right
    v, _ = steerer_command(path, box, lateral, None, 0.0)
    assert (v < 0.3) is faster
    assert steerer_command(path, None, lateral, None, 0.0) == (0.3, 0.0)
    assert steerer_command(path, box, 0.0, None, 0.0)[0] == 0.3  # no lever arm: just push
