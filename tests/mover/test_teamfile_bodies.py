"""A team file's robots placed by a continuous world are checked against the world file's
``[[robots]]`` (issue 28: a misspelt ``mosely`` passed ``--check`` and got a default body)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mover._up._teamfile import TeamFileError, parse_team

WORLD = '[world]\nsize = [4.0, 4.0]\n\n[[robots]]\nid = "ernst"\n\n[[robots]]\nid = "moseley"\n'
TEAM = '[team]\nname = "t"\n\n[world]\nfile = "w.toml"\n\n[[robots]]\n'


def plan(tmp_path: Path, robots: str, world: str = WORLD) -> list[str]:
    (tmp_path / "w.toml").write_text(world)
    return parse_team(TEAM + robots, tmp_path / "team.toml").robots()


def test_a_misspelt_robot_is_named_with_its_line_and_the_world_file_robots(
    tmp_path: Path,
) -> None:
    with pytest.raises(TeamFileError) as caught:
        plan(tmp_path, 'names = ["ernst", "mosely"]\n')
    assert str(caught.value) == (
        f"{tmp_path / 'team.toml'}:8: robots[0].names[1]: 'mosely' is not a robot of w.toml "
        "(did you mean 'moseley'?); its robots: ernst, moseley"
    )


def test_counted_names_are_checked_too(tmp_path: Path) -> None:
    with pytest.raises(TeamFileError, match=r":8: robots\[0\].prefix: 'r1' is not a robot"):
        plan(tmp_path, 'prefix = "r"\ncount = 2\n')


def test_robots_the_team_file_places_or_a_world_that_lists_none_take_any_name(
    tmp_path: Path,
) -> None:
    placed = 'names = ["mosely"]\nposes = [[1.0, 1.0, 0.0]]\n'
    assert plan(tmp_path, placed) == ["mosely"]
    assert plan(tmp_path, 'names = ["mosely"]\n', world="[world]\nsize = [4.0, 4.0]\n") == [
        "mosely"
    ]
    assert plan(tmp_path, 'names = ["ernst", "moseley"]\n') == ["ernst", "moseley"]
