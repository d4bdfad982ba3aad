"""A step's loss and its tasks, with the nodes in this process (real zenoh on 127.0.0.1): a
member lost before any other reached the step still fails it, a member in its AND operation is
told, and the designated member's questions end, awaited, with the step. Over real processes,
at every phase boundary: tests/mover/test_step_liveness.py."""

from __future__ import annotations

import asyncio
import time
from functools import partial

import pytest

from mover import MemberLost, Node, RunTeam
from mover._collective._step import LOST_GRACE
from tests.mover.test_simtime_or import FakeWorld, timed_teams, walker

BOUND = LOST_GRACE + 2.0  # seconds: a closed node is seen gone at once


async def lose(node: Node, others: list[Node]) -> float:
    """Close ``node`` (as if its process died); when."""
    await node.close()
    for other in others:
        await other.membership.wait_gone(node.name, timeout=5)
    return time.monotonic()


@pytest.mark.parametrize("late", [True, False], ids=["lost-before-the-step", "lost-inside"])
async def test_a_member_lost_before_or_during_the_and_fails_it_for_all(
    nodes: list[Node], late: bool
) -> None:
    """``late``: the others reach the AND only once the loss is counted (search and rescue's
    robots still driving to the object when one of them died); else they hold in their
    operation, which is cancelled."""
    names = [n.name for n in nodes]
    teams = [RunTeam(n, "loss", names) for n in nodes[:4]]
    cancelled: list[str] = []

    async def hold(team: RunTeam) -> str:
        try:
            await asyncio.sleep(3600)
        finally:
            cancelled.append(team.me)
        return team.me

    if late:
        lost_at = await lose(nodes[4], nodes[:4])
        await asyncio.sleep(LOST_GRACE + 0.2)  # counted lost before any member reached the step
        steps = [asyncio.ensure_future(t.distributed_and(lambda: asyncio.sleep(0))) for t in teams]
    else:
        steps = [asyncio.ensure_future(t.distributed_and(partial(hold, t))) for t in teams]
        await asyncio.sleep(0.2)
        lost_at = await lose(nodes[4], nodes[:4])
    done, _ = await asyncio.wait(steps, timeout=BOUND + LOST_GRACE + 0.2)
    assert len(done) == len(steps), "a member still waits in the step"
    for step in steps:
        with pytest.raises(MemberLost) as lost:
            step.result()
        assert lost.value.members == {"n4"}
    assert time.monotonic() - lost_at < BOUND + LOST_GRACE + 0.2
    assert sorted(cancelled) == ([] if late else names[:4])


async def test_the_designated_members_questions_end_with_its_step(nodes: list[Node]) -> None:
    """A timed OR: the designated member (n0) asks the others ``or_passed``; when its own member
    leaves the step, every question it asked has ended (they belong to the step's group)."""
    world = FakeWorld()
    teams, fake = timed_teams(nodes, world, "owned-step")
    ops = {name: walker(clock, 0.2 if name == "n1" else 1e9) for name, clock in fake.items()}
    steps = [asyncio.ensure_future(t.distributed_or(ops[t.me])) for t in teams]
    async with asyncio.timeout(20):
        outcome = await steps[0]
    state = teams[0].collectives._steps[("owned-step", 1)]
    assert outcome.winner == "n1"
    assert state.questions > 0 and state.asking  # it did ask
    assert state.owner is not None and state.owner.done()
    assert all(q.done() for q in state.asking.values())
    async with asyncio.timeout(20):
        assert {o.winner for o in await asyncio.gather(*steps)} == {"n1"}
