"""The foot-bot's navigation (Ducatelle et al., 4.3-4.4): instructions, the forward/backward
rule, LEDs, and what it does without an instruction."""

import math

import numpy as np
import pytest

from robots.stigmergic import FootBot, FootPerception, Goal, Heard, Mode, Motion


def _bot(goal: Goal = Goal.TARGET) -> FootBot:
    return FootBot(np.random.default_rng(3), goal, Motion(d=2.0, speed=0.3))


def _mode(bot: FootBot) -> Mode:
    """The bot's mode, read afresh (a type checker keeps what an earlier assert narrowed)."""
    return bot.mode


def _heard(eyebot: str, to_target: float, reference: float = 0.0) -> Heard:
    return Heard(eyebot, reference=reference, to_source=0.0, to_target=to_target)


def test_it_turns_to_theta_0_plus_theta_t_then_drives_with_its_front_led_on() -> None:
    bot = _bot()
    # θ0 seen at +90° in its frame, θ_t = +30° from θ0: drive at 120° from its heading (0)
    cmd = bot.step(FootPerception(pose=(0, 0, 0.0), heard=_heard("e1", math.pi / 6, math.pi / 2)))
    assert bot.mode is Mode.FOLLOW and bot.heading == pytest.approx(2 * math.pi / 3)
    assert cmd.v == 0.0 and cmd.w > 0.0  # turning first, its front LED off meanwhile
    assert cmd.front is None and not cmd.avoiding
    cmd = bot.step(FootPerception(pose=(0, 0, 2 * math.pi / 3)))
    assert cmd.v == 0.3 and cmd.w == pytest.approx(0.0) and cmd.front is Goal.TARGET


def test_a_forward_instruction_is_followed_and_its_eye_bot_is_ignored_after() -> None:
    bot = _bot()
    bot.step(FootPerception(pose=(0, 0, 0), heard=_heard("e1", 0.0)))  # first: forward, east
    bot.step(FootPerception(pose=(1, 0, 0), heard=_heard("e2", math.pi / 3)))  # 60°: forward
    assert bot.heading == pytest.approx(math.pi / 3) and not bot.backward
    bot.step(FootPerception(pose=(1, 0, 0), heard=_heard("e2", math.pi)))  # e2 again: ignored
    assert bot.heading == pytest.approx(math.pi / 3)


def test_a_backward_instruction_is_followed_with_the_led_off_while_listening_on() -> None:
    bot = _bot()
    bot.step(FootPerception(pose=(0, 0, 0), heard=_heard("e1", 0.0)))  # east
    cmd = bot.step(FootPerception(pose=(2, 0, 0), heard=_heard("e2", math.pi)))  # west: backward
    assert bot.backward and bot.heading == pytest.approx(math.pi) and cmd.front is None
    # e2 insists on going back: the foot-bot keeps going back, still listening
    cmd = bot.step(FootPerception(pose=(2, 0, 0.0), heard=_heard("e2", -2.5)))
    assert bot.backward and bot.heading == pytest.approx(-2.5) and cmd.front is None
    # then e2 sends a forward direction (relative to e1's east): taken, and e2 no longer heard
    cmd = bot.step(FootPerception(pose=(2, 0, 0.0), heard=_heard("e2", 0.4)))
    assert not bot.backward and bot.heading == pytest.approx(0.4) and cmd.front is None
    cmd = bot.step(FootPerception(pose=(2, 0, 0.4)))  # turned: it drives, its front LED on
    assert cmd.front is Goal.TARGET
    bot.step(FootPerception(pose=(2, 0, 0.0), heard=_heard("e2", math.pi)))
    assert bot.heading == pytest.approx(0.4)


def test_forward_is_judged_against_the_previous_eye_bot_not_the_current_heading() -> None:
    bot = _bot()
    bot.step(FootPerception(pose=(0, 0, 0), heard=_heard("e1", 0.0)))  # east
    bot.step(FootPerception(pose=(2, 0, 0), heard=_heard("e2", 1.4)))  # 80°: forward
    # under e3, 150° is 70° off e2's 80° (though 150° off e1's east): forward
    bot.step(FootPerception(pose=(2, 2, 0.0), heard=_heard("e3", math.radians(150))))
    assert not bot.backward
    # under e4, -60° is 150° off e3's 150°: backward
    bot.step(FootPerception(pose=(0, 3, 0.0), heard=_heard("e4", math.radians(-60))))
    assert bot.backward


def test_after_d_metres_it_heads_for_the_closest_eye_bot_in_view_but_not_the_last() -> None:
    bot = _bot()
    bot.step(FootPerception(pose=(0, 0, 0), heard=_heard("e1", 0.0)))
    bot.step(FootPerception(pose=(1.0, 0, 0)))
    assert bot.mode is Mode.FOLLOW
    # 2 m driven; e1 (behind, at the origin) and another eye-bot ahead-left are in view
    cmd = bot.step(FootPerception(pose=(2.1, 0, 0), eyebots=[(2.1, math.pi), (3.0, 0.5)]))
    assert _mode(bot) is Mode.SEEK and bot.heading == pytest.approx(0.5)
    assert cmd.front is None


def test_with_no_eye_bot_in_view_it_moves_at_random_with_its_led_off() -> None:
    bot = _bot()
    cmd = bot.step(FootPerception(pose=(0, 0, 0)))
    assert bot.mode is Mode.RANDOM and 0.5 <= bot.left <= 2.0 and cmd.front is None
    first = bot.heading
    bot.step(FootPerception(pose=(0, 0, 0)))
    assert bot.heading == first  # keeps its random leg until it is driven
    assert isinstance(first, float)


def test_obstacles_are_avoided_with_the_beacon_saying_so() -> None:
    bot = _bot()
    bot.step(FootPerception(pose=(0, 0, 0), heard=_heard("e1", 0.0)))
    cmd = bot.step(FootPerception(pose=(0.1, 0, 0), obstacle=0.3))  # ahead, a little left
    assert cmd.avoiding and cmd.front is None and cmd.w < 0 and cmd.v == 0.0
    # it keeps turning the same way while the obstacle is ahead, even seen on the other side
    cmd = bot.step(FootPerception(pose=(0.1, 0, -0.4), obstacle=-0.1))
    assert cmd.avoiding and cmd.w < 0
    # clear: straight on for a moment, LEDs plain and off, then back to its way (east)
    cmd = bot.step(FootPerception(pose=(0.1, 0, -0.8)))
    assert (cmd.v, cmd.w, cmd.avoiding, cmd.front) == (0.3, 0.0, False, None)
    cmd = bot.step(FootPerception(pose=(0.5, -0.3, -0.8)))
    assert cmd.w > 0 and cmd.v == 0.0 and cmd.front is None
    cmd = bot.step(FootPerception(pose=(0.5, -0.3, 0.0)))
    assert cmd.v > 0 and cmd.front is Goal.TARGET
    other = _bot()
    cmd = other.step(FootPerception(pose=(0, 0, 0), obstacle=-1.2))  # right side: turn left
    assert cmd.avoiding and cmd.w > 0 and cmd.v > 0
    cmd = other.step(FootPerception(pose=(0, 0, 0), obstacle=2.5))  # behind: not avoided
    assert not cmd.avoiding


def test_reaching_the_goal_turns_it_over_and_forgets_the_way() -> None:
    bot = _bot()
    bot.step(FootPerception(pose=(0, 0, 0), heard=_heard("e1", 0.0)))
    cmd = bot.step(FootPerception(pose=(1, 0, 0), at_target=True, heard=_heard("e9", math.pi)))
    assert bot.goal is Goal.SOURCE and bot.trips == 1
    # the first instruction after the goal is forward (nothing to compare with); θ_s = 0 here
    assert not bot.backward and cmd.front is Goal.SOURCE
    bot.step(FootPerception(pose=(1, 0, 0), at_source=False, at_target=False))
    assert bot.goal is Goal.SOURCE


def test_the_same_seed_gives_the_same_walk() -> None:
    def walk(seed: int) -> list[tuple[float, float]]:
        bot = FootBot(np.random.default_rng(seed))
        out = []
        for k in range(40):
            cmd = bot.step(FootPerception(pose=(0.05 * k, 0, 0.1 * k)))
            out.append((cmd.v, cmd.w))
        return out

    assert walk(11) == walk(11)
    assert walk(11) != walk(12)


def _head_on_turn(seed: int, motion: Motion) -> float:
    bot = FootBot(np.random.default_rng(seed), Goal.TARGET, motion)
    return bot.step(FootPerception(pose=(0, 0, 0), obstacle=0.0)).w


def test_an_obstacle_straight_ahead_is_passed_on_either_side_by_a_seeded_coin() -> None:
    turns = [_head_on_turn(seed, Motion()) for seed in range(200)]
    left = sum(w > 0 for w in turns)
    assert all(w != 0 for w in turns)
    assert 70 < left < 130  # no side bias (200 fair coins: 100 ± 7)
    assert turns == [_head_on_turn(seed, Motion()) for seed in range(200)]  # seeded


def test_the_old_head_on_rule_always_passes_right() -> None:
    assert all(_head_on_turn(seed, Motion(head_on_right=True)) < 0 for seed in range(20))
