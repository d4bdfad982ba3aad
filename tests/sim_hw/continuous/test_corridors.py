"""The double corridor of Ducatelle et al. (Fig. 3): the left corridor is ratio times as long,
both are clear along their middle lines, and they are walled off from each other."""

import itertools
import math

import pytest

from sim_hw.continuous import World, corridor_paths, double_corridor


def _length(line: tuple[tuple[float, float], ...]) -> float:
    return sum(math.dist(a, b) for a, b in itertools.pairwise(line))


@pytest.mark.parametrize("ratio", [1.0, 1.5, 2.0])
def test_the_left_corridor_is_ratio_times_the_right_one(ratio: float) -> None:
    paths = corridor_paths(length=20.0, ratio=ratio)
    assert _length(paths["right"]) == pytest.approx(20.0)
    assert _length(paths["left"]) == pytest.approx(20.0 * ratio)
    spec = double_corridor(length=20.0, ratio=ratio)
    marks = {m.id: m.center for m in spec.markers}
    # source and target lie half-way between the corridors' mouths
    for end, mark in ((0, "source"), (-1, "target")):
        right, left = paths["right"][end], paths["left"][end]
        assert math.dist(marks[mark], right) == pytest.approx(math.dist(marks[mark], left))


@pytest.mark.parametrize("ratio", [1.0, 2.0])
def test_the_corridors_are_clear_and_walled_off(ratio: float) -> None:
    spec = double_corridor(length=20.0, ratio=ratio)
    world = World(spec)
    paths = corridor_paths(length=20.0, ratio=ratio)
    solid = world.space.shapes

    def blocked(x: float, y: float, r: float) -> bool:
        return any(s.point_query((x, y)).distance < r for s in solid if not s.sensor)

    for line in paths.values():
        for (ax, ay), (bx, by) in itertools.pairwise(line):
            for k in range(21):
                f = k / 20
                assert not blocked(ax + f * (bx - ax), ay + f * (by - ay), 0.3)
    # half-way up, between the two corridors, there is wall
    (rx, _), (lx, _) = paths["right"][0], paths["left"][0]
    assert blocked((rx + lx) / 2, spec.size[1] / 2, 0.1)
