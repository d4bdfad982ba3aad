"""The race program on real processes: a lock-step world and two robot processes over zenoh,
started by mover's pytest plugin (installing mover enables it)."""

from mover import Node, launch
from mover.pytest_plugin import Starter


async def test_one_robot_wins_the_race(
    mover_world: Starter, mover_robots: Starter, mover_launcher: Node
) -> None:
    await mover_world("../worlds/two_robots.toml", expect=2)  # relative to this file
    await mover_robots("ada", "bob")
    outcomes = await launch(mover_launcher, "race", ["ada", "bob"], {"distance": 0.5}, run="r1")
    winners = {o["result"]["winner"] for o in outcomes.values()}
    assert len(winners) == 1 and winners <= {"ada", "bob"}, outcomes
