"""The eye-bot's policies: eq. 1, the 12 directions, the draw rule (Ducatelle et al., 4.2)."""

import math

import numpy as np
import pytest

from robots.stigmergic import (
    DIRECTIONS,
    SPACING,
    Learning,
    Policy,
    direction_angle,
    direction_index,
)


def test_a_policy_starts_uniform_at_one_twelfth() -> None:
    assert Policy().preferences == tuple([1.0 / 12] * 12)


def test_eq_1_adds_c_a_and_multiplies_by_c_m() -> None:
    p = Policy()
    p.increase(3, 0.5)
    p.increase(3, 0.5)
    p.decrease(5, 0.99)
    p.decrease(5, 0.99)
    assert p.preferences[3] == pytest.approx(1 / 12 + 1.0, abs=1e-15)
    assert p.preferences[5] == pytest.approx(1 / 12 * 0.99**2, abs=1e-15)
    assert [v for i, v in enumerate(p.preferences) if i not in (3, 5)] == [1 / 12] * 10


def test_angles_go_to_the_nearest_of_twelve_directions() -> None:
    for i in range(DIRECTIONS):
        centre = i * SPACING
        for off in (-0.49 * SPACING, 0.0, 0.49 * SPACING):
            assert direction_index(centre + off) == i
            assert direction_index(centre + off - 2 * math.pi) == i
        assert direction_angle(i) == pytest.approx(math.remainder(centre, 2 * math.pi))
    assert direction_index(math.pi) == 6 and direction_index(-math.pi) == 6


def test_the_learning_constants_are_checked() -> None:
    assert Learning() == Learning(c_a=0.5, c_m=0.99, q=0.5)
    for bad in ({"c_m": 1.0}, {"c_m": -0.1}, {"q": 1.5}, {"c_a": 0.0}):
        with pytest.raises(ValueError, match="must be"):
            Learning(**bad)


def _frequencies(policy: Policy, q: float, n: int = 10_000, seed: int = 7) -> np.ndarray:
    rng = np.random.default_rng(seed)
    counts = np.bincount([policy.draw(rng, q) for _ in range(n)], minlength=DIRECTIONS)
    return counts / n


def _within(freq: np.ndarray, expected: np.ndarray, n: int = 10_000) -> None:
    sd = np.sqrt(expected * (1 - expected) / n)
    assert np.all(np.abs(freq - expected) <= 4 * sd + 1e-12), (freq, expected)


def test_draws_take_the_best_with_probability_q_else_proportionally() -> None:
    p = Policy()
    p.prefs[:] = 1.0
    p.prefs[4] = 3.0  # total 14
    proportional = p.prefs / p.prefs.sum()
    _within(_frequencies(p, q=0.0), proportional)
    best = np.zeros(DIRECTIONS)
    best[4] = 1.0
    _within(_frequencies(p, q=0.5), 0.5 * best + 0.5 * proportional)
    assert _frequencies(p, q=1.0)[4] == 1.0


def test_an_untrained_policy_draws_uniformly_even_when_greedy() -> None:
    _within(_frequencies(Policy(), q=1.0), np.full(DIRECTIONS, 1 / 12))


def test_a_proportional_draw_is_the_one_numpy_choice_makes() -> None:
    # the draw without rng.choice's checks: the same index from the same stream, so that runs
    # saved before it came are made again the same
    prefs = np.random.default_rng(0).random(DIRECTIONS) * 3.0
    policy = Policy(prefs.copy())
    mine, theirs = np.random.default_rng(42), np.random.default_rng(42)
    for _ in range(2000):
        theirs.random()  # the draw's greedy-or-not coin (q = 0: never greedy)
        want = int(theirs.choice(DIRECTIONS, p=prefs / float(prefs.sum())))
        assert policy.draw(mine, q=0.0) == want
