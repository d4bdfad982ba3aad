"""The Lévy search's rules without a world: the step generator (eq. 11-12), Viswanathan's
estimate (eq. 4-5), the repulsion (eq. 9) and the controller (eq. 10, Fig. 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robots.hal import Sighting
from robots.library import (
    MARKED,
    FixedSteps,
    LevyParams,
    LevySense,
    LevySteps,
    LevyWalker,
    mantegna,
    mean_flights,
    repulsion,
    stable_alpha,
    viswanathan_mu,
    walker,
)

N = 100_000


def hill(samples: np.ndarray, k: int = 1000) -> float:
    """Hill's estimate of the tail exponent of |samples| from its ``k`` largest values."""
    top = np.sort(np.abs(samples))[::-1]
    return float(1.0 / np.mean(np.log(top[:k] / top[k])))


@pytest.mark.parametrize("alpha", [1.0, 1.5])
@pytest.mark.parametrize("correction", [False, True])
def test_the_tail_exponent_fitted_on_1e5_steps_is_alpha_within_10_percent(
    alpha: float, correction: bool
) -> None:
    z = mantegna(np.random.default_rng(11), alpha, N, correction=correction)
    # P(|z| > l) ~ l^-α, that is the density P(l) ~ l^-(1+α) = l^-μ
    assert hill(z) == pytest.approx(alpha, rel=0.10)


def test_alpha_2_is_gaussian() -> None:
    z = mantegna(np.random.default_rng(3), 2.0, N)
    sd = float(np.std(z))
    assert sd == pytest.approx(math.sqrt(2.0), rel=0.02)  # eq. 1 at α = 2, γ = 1: variance 2
    kurtosis = float(np.mean((z - z.mean()) ** 4) / sd**4)
    assert kurtosis == pytest.approx(3.0, abs=0.1)
    for k, share in ((1, 0.6827), (2, 0.9545), (3, 0.9973)):
        assert np.mean(np.abs(z) < k * sd) == pytest.approx(share, abs=0.005)


def test_a_heavier_tail_below_2() -> None:
    z = mantegna(np.random.default_rng(3), 1.5, N)
    sd = float(np.std(z))
    assert float(np.mean((z - z.mean()) ** 4) / sd**4) > 10


def test_bad_alphas_are_refused() -> None:
    rng = np.random.default_rng(0)
    for alpha in (0.0, -1.0, 2.01):
        with pytest.raises(ValueError, match="alpha must be in"):
            mantegna(rng, alpha, 10)
    with pytest.raises(ValueError, match="correction holds"):
        mantegna(rng, 0.5, 10, correction=True)


def test_steps_are_scaled_capped_and_seeded() -> None:
    a = LevySteps(np.random.default_rng(5), alpha=0.5, scale=2.0, cap=7.0)
    b = LevySteps(np.random.default_rng(5), alpha=0.5, scale=2.0, cap=7.0)
    drawn = [a.draw() for _ in range(300)]
    assert drawn == [b.draw() for _ in range(300)]
    assert max(drawn) == 7.0 and min(drawn) >= 0.0
    assert FixedSteps(1.5).draw() == 1.5


def test_viswanathans_estimate() -> None:
    # eq. 4-5: α (the paper's, that is μ) = 2 - 1/ln²(λ/r_v)
    assert viswanathan_mu(math.e**2, 1.0) == pytest.approx(2.0 - 1.0 / 4.0)
    assert viswanathan_mu(1e6, 1.0) > 1.99
    assert stable_alpha(2.0) == 1.0
    assert mean_flights(100.0, 1.0, 2.0) == pytest.approx(10.0)  # eq. 3
    with pytest.raises(ValueError, match="lam > r_v"):
        viswanathan_mu(1.0, 2.0)


def test_the_repulsion_is_eq_9_and_zero_beyond_its_range() -> None:
    # ρ = 0.5 straight ahead, ρ0 = 1.5, k = 2: 2 (1/0.5 - 1/1.5) / 0.5² = 10.667, pointing back
    fx, fy = repulsion([(0.5, 0.0)], k_rep=2.0, rho0=1.5)
    assert (fx, fy) == pytest.approx((-32.0 / 3.0, 0.0))
    # ρ = 1 on the left: (1 - 1/1.5) / 1 = 1/3, pointing right
    fx, fy = repulsion([(1.0, math.pi / 2)], k_rep=1.0, rho0=1.5)
    assert (fx, fy) == pytest.approx((0.0, -1.0 / 3.0))
    # superposition of the two
    both = repulsion([(0.5, 0.0), (1.0, math.pi / 2)], k_rep=1.0, rho0=1.5)
    assert both == pytest.approx((-16.0 / 3.0, -1.0 / 3.0))
    assert repulsion([(1.6, 0.3), (1.5, 1.0), (3.0, 2.0)], k_rep=1.0, rho0=1.5) == (0.0, 0.0)


def sense(**kw: object) -> LevySense:
    base: dict[str, object] = {
        "dt": 0.1,
        "sonar": (3.0,) * 8,
        "angles": tuple(2 * math.pi * i / 8 for i in range(8)),
    }
    base.update(kw)
    return LevySense(**base)  # type: ignore[arg-type]


def target(range_: float, bearing: float, status: str = "", tid: str = "t0") -> Sighting:
    return Sighting("target", tid, status, range_, bearing)


def test_a_marked_target_turns_away_a_robot_within_the_signature_range() -> None:
    lp = walker("L+P", np.random.default_rng(1))
    lone = walker("L", np.random.default_rng(1))
    near = sense(targets=(target(2.0, 0.3, MARKED),))
    cmd = lp.step(near)
    assert cmd.state == "field" and cmd.w < 0  # the target is on the left: turn right
    assert lone.step(near).w == 0.0  # the plain Lévy walk ignores signatures
    far = walker("L+P", np.random.default_rng(1)).step(sense(targets=(target(3.2, 0.3, MARKED),)))
    assert far.w == 0.0 and far.state == "move"
    unmarked = walker("L+P", np.random.default_rng(1)).step(sense(targets=(target(2.0, 0.3),)))
    assert unmarked.w == 0.0


def test_the_finder_is_not_turned_back_by_its_own_mark() -> None:
    finder = walker("L+P", np.random.default_rng(1))
    assert finder.step(sense(targets=(target(0.8, 0.3),))).mark == "t0"
    mine = (target(0.8, 0.3, MARKED), target(2.5, -0.3, MARKED, "t1"))
    assert finder.step(sense(targets=mine[:1])).w == 0.0  # "other robots" avoid it (V-B)
    assert finder.step(sense(targets=mine)).w > 0  # t1 was someone else's find
    both = walker("L+P", np.random.default_rng(1), params=LevyParams(own_signatures=True))
    both.step(sense(targets=(target(0.8, 0.3),)))
    assert both.step(sense(targets=mine[:1])).w < 0


def test_robots_within_rho0_turn_a_robot_away_but_obstacles_do_not() -> None:
    lp = walker("L+P", np.random.default_rng(1))
    cmd = lp.step(sense(neighbours=((1.0, -0.5),)))
    assert cmd.state == "field" and cmd.w > 0  # the robot is on the right: turn left
    plain = walker("L", np.random.default_rng(1)).step(sense(neighbours=((1.0, -0.5),)))
    assert plain.w == 0.0
    # a wall 1 m ahead on the sonar: no force, only avoidance once it is near
    assert walker("L+P", np.random.default_rng(1)).step(sense(sonar=(1.0,) * 8)).w == 0.0


def test_a_target_within_sensing_range_is_caught_and_marked_once() -> None:
    w = walker("FL", np.random.default_rng(2))
    assert w.step(sense(targets=(target(1.5, 0.0),))).mark is None  # beyond r_v = 1 m
    got = w.step(sense(targets=(target(0.9, 0.2),)))
    assert got.state == "catch" and got.mark == "t0" and got.v == 0.0
    assert w.step(sense(targets=(target(0.9, 0.2),))).mark is None  # not again at once
    assert w.step(sense(targets=(target(0.9, 0.2, MARKED),))).mark is None
    assert w.marked == {"t0"}


def test_move_and_turn_phases_alternate_as_eq_10() -> None:
    w = LevyWalker(FixedSteps(0.6), np.random.default_rng(4), LevyParams(speed=0.6))
    states = [w.step(sense()).state for _ in range(30)]
    # 0.6 m at 0.6 m/s is 10 ticks of L = 1, then turn_time = 1 s of L = 0
    assert states[:10] == ["move"] * 10
    assert states[10:20] == ["turn"] * 10
    assert states[20:30] == ["move"] * 10
    cmds = [w.step(sense()) for _ in range(10)]
    assert len({c.w for c in cmds}) == 1 and cmds[0].v == 0.0  # one Gaussian ω a turn phase


def test_an_obstacle_ahead_ends_the_step_and_the_robot_turns_to_the_free_side() -> None:
    w = walker("L", np.random.default_rng(4))
    blocked = (0.2, 0.2, 2.0, 3.0, 3.0, 3.0, 0.5, 0.2)  # free on the left (rays 2-3)
    cmd = w.step(sense(sonar=blocked))
    assert cmd.state == "avoid" and cmd.v == 0.0 and cmd.w > 0
    assert w.step(sense(sonar=blocked)).state == "avoid"
    first = w.phases
    assert w.step(sense()).state == "move" and w.phases == first + 1  # a new step


def test_the_parts_of_l_p_each_react_to_one_thing_only() -> None:
    robot = sense(neighbours=((1.0, -0.5),))  # a robot on the right
    found = sense(targets=(target(2.0, 0.3, MARKED),))  # someone's find on the left
    for method, to_robot, to_find in (
        ("L+F", True, False),
        ("L+S", False, True),
        ("FL+S", False, True),
        ("L+P", True, True),
    ):
        assert (walker(method, np.random.default_rng(1)).step(robot).w > 0) is to_robot, method
        assert (walker(method, np.random.default_rng(1)).step(found).w < 0) is to_find, method
    # FL+S keeps the fixed steps, L+S the Lévy ones
    fls = walker("FL+S", np.random.default_rng(1), fixed=1.0)
    assert isinstance(fls.steps, FixedSteps) and fls.steps.length == 1.0
    assert isinstance(walker("L+S", np.random.default_rng(1)).steps, LevySteps)


def test_unknown_methods_are_refused() -> None:
    with pytest.raises(ValueError, match="unknown method"):
        walker("brownian", np.random.default_rng(0))
