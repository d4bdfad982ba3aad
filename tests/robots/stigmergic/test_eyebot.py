"""The eye-bot's observations (Ducatelle et al., 4.1-4.2): θ_f read off a foot-bot's LEDs."""

import math

import numpy as np
import pytest

from robots.stigmergic import (
    SPACING,
    EyeBot,
    FootBotSeen,
    Goal,
    Reading,
    direction_index,
    trip_weight,
)


def _moving(
    heading: float, at: tuple[float, float] = (0.5, -0.3), goal: Goal = Goal.TARGET
) -> FootBotSeen:
    front = (at[0] + 0.1 * math.cos(heading), at[1] + 0.1 * math.sin(heading))
    return FootBotSeen(beacon=at, front=front, goal=goal)


def test_theta_f_is_read_off_the_leds_within_the_twelve_directions() -> None:
    for i in range(12):
        for off in (-0.45 * SPACING, 0.0, 0.45 * SPACING):
            heading = i * SPACING + off
            came_from = _moving(heading).came_from()
            assert came_from is not None
            assert direction_index(came_from) == (i + 6) % 12


def test_a_foot_bot_going_to_the_target_teaches_the_way_to_the_source() -> None:
    eye = EyeBot(np.random.default_rng(0))
    eye.observe([_moving(0.0, at=(-0.5, -0.3))])  # heading east: it comes from the west (6)
    assert eye.to_source.preferences[6] == pytest.approx(1 / 12 + 0.5)
    assert eye.to_target.preferences[6] == pytest.approx(1 / 12 * 0.99)
    assert sum(eye.to_source.preferences) == pytest.approx(1.5)


def test_a_foot_bot_going_to_the_source_teaches_the_way_to_the_target() -> None:
    eye = EyeBot(np.random.default_rng(0))
    eye.observe([_moving(math.pi / 2, goal=Goal.SOURCE)])  # going north: it comes from the south
    assert eye.to_target.preferences[9] == pytest.approx(1 / 12 + 0.5)
    assert eye.to_source.preferences[9] == pytest.approx(1 / 12 * 0.99)


@pytest.mark.parametrize(
    ("at", "heading", "coming"),
    [
        ((0.5, 0.0), math.pi, True),  # east of the eye-bot, heading west: straight at it
        ((0.5, 0.0), 0.0, False),  # east of it, heading east: straight away
        ((-0.5, 0.0), 0.0, True),  # west of it, heading east
        ((0.0, 0.8), -math.pi / 2, True),  # north of it, heading south
        ((0.0, 0.8), math.pi / 2, False),  # north of it, heading north
        ((0.5, 0.0), math.pi - 1.4, True),  # 80° off the line to the eye-bot: still closing in
        ((0.5, 0.0), math.pi + 1.4, True),  # the same on the other side
        ((0.5, 0.0), math.pi - 1.7, False),  # 97° off: drawing away, if slowly
        ((0.5, 0.0), math.pi + 1.7, False),
        ((0.01, 0.0), math.pi, False),  # right under it: neither coming nor going
    ],
)
def test_coming_towards_reads_the_heading_against_where_it_is_seen(
    at: tuple[float, float], heading: float, coming: bool
) -> None:
    assert _moving(heading, at=at).coming_towards() is coming


def test_a_foot_bot_with_its_front_led_off_is_not_coming_towards() -> None:
    assert not FootBotSeen(beacon=(0.5, 0.0), goal=Goal.TARGET).coming_towards()


def test_a_foot_bot_leaving_teaches_nothing_unless_the_old_reading_is_asked_for() -> None:
    leaving = _moving(0.0, at=(0.5, 0.0))  # east of the eye-bot, heading east
    new, old = (
        EyeBot(np.random.default_rng(0)),
        EyeBot(np.random.default_rng(0), reading=Reading.ANY),
    )
    new.observe([leaving])
    old.observe([leaving])
    assert new.to_source.preferences == new.to_target.preferences == tuple([1 / 12] * 12)
    # the old reading: the way it leaves, reversed, is taken for the way it came (an echo)
    assert old.to_source.preferences[6] == pytest.approx(1 / 12 + 0.5)


def test_avoiding_marks_the_direction_where_it_is_seen_as_blocked() -> None:
    eye = EyeBot(np.random.default_rng(0))
    eye.observe([FootBotSeen(beacon=(0.0, 1.0), avoiding=True)])  # seen to the north (index 3)
    assert eye.to_source.preferences[3] == pytest.approx(1 / 12 * 0.99)
    assert eye.to_target.preferences[3] == pytest.approx(1 / 12 * 0.99)
    assert sum(eye.to_source.preferences) == pytest.approx(11 / 12 + 0.99 / 12)


def test_a_front_led_off_teaches_nothing() -> None:
    eye = EyeBot(np.random.default_rng(0))
    eye.observe([FootBotSeen(beacon=(0.3, 0.3)), FootBotSeen(beacon=(0.1, 0.0), goal=Goal.TARGET)])
    assert eye.to_source.preferences == eye.to_target.preferences == tuple([1 / 12] * 12)


def test_a_pre_programmed_eye_bot_always_shows_its_directions() -> None:
    eye = EyeBot(np.random.default_rng(1))
    eye.show_shortest(to_source=math.pi / 2, to_target=-math.pi / 2)
    eye.observe([_moving(0.0)] * 50)
    draws = {eye.instruct() for _ in range(200)}
    assert len(draws) == 1
    (only,) = draws
    assert only.to_source == pytest.approx(math.pi / 2)
    assert only.to_target == pytest.approx(-math.pi / 2)


def test_an_instruction_is_the_same_for_the_same_seed() -> None:
    a, b = EyeBot(np.random.default_rng(5)), EyeBot(np.random.default_rng(5))
    seen = [_moving(0.3), FootBotSeen(beacon=(0.2, -0.4), avoiding=True)]
    assert [a.step(seen) for _ in range(50)] == [b.step(seen) for _ in range(50)]


def test_trip_weights_favour_quick_trips_within_bounds() -> None:
    assert trip_weight(60.0, 60.0) == 1.0
    assert trip_weight(30.0, 60.0) == 2.0
    assert trip_weight(600.0, 60.0) == 0.25
    assert trip_weight(1.0, 60.0) == 4.0
    assert trip_weight(0.0, 60.0) == 1.0
