"""A successor taking a step over from a designated member that died: it ends every member's
wait, with the decision the dead one made if any live member holds it (nodes in this process,
real zenoh on 127.0.0.1; what the dead member told whom is set by hand).

The interleaving CI saw once under load (issue 22, "or-deciding-a"): the designated member a
decided the run's first AND and died; c had its answer and went on, b's answer never came. b
took the step over and decided it "lost" (agreement broken: c holds "all"), so b's run ended,
and c, in the next step, asked b, which waited for its own member to join: c hung.
"""

from __future__ import annotations

import asyncio

import pytest

from mover import MemberLost, Node, RunTeam
from mover._collective import Collectives, Decision
from mover._collective._step import LOST_GRACE

BOUND = LOST_GRACE + 2.0  # seconds: the dead member is gone already when the step starts
RUN = "takeover"


async def hold() -> str:
    await asyncio.sleep(3600)
    return "never"


async def dead(nodes: list[Node]) -> list[str]:
    """n0 (the designated member of [n0, n1, n2]) dies, and n1 and n2 see it gone: the
    members."""
    n0, n1, n2 = nodes[:3]
    await n0.close()
    for node in (n1, n2):
        await node.membership.wait_gone("n0", timeout=10)
    return ["n0", "n1", "n2"]


async def test_a_successor_adopts_the_and_decision_a_member_was_told(nodes: list[Node]) -> None:
    """n0 decided AND step 1 and told n2, which went on; n1's answer was lost with n0. n1
    takes the step over: it ends with n0's decision, as n2 did, not with "lost"."""
    told = Decision("all", results={"n0": 0, "n1": 1, "n2": 2})
    Collectives(nodes[2]).learned(RUN, 1, told)  # n2's answer from n0
    members = await dead(nodes)
    b = RunTeam(nodes[1], RUN, members)
    async with asyncio.timeout(BOUND):
        results = await b.distributed_and(lambda: asyncio.sleep(0, 1))
    assert results == told.results


async def test_a_successor_adopts_the_or_decision_a_member_moved_on_with(
    nodes: list[Node],
) -> None:
    """n0 decided OR step 1 and n2 heard it and went on; n1 did not. n1 takes the step over:
    it ends with n2's decision (it used to wait for n2 to join a step n2 had left)."""
    heard = Decision("won", winner="n2", result=7)
    Collectives(nodes[2]).learned(RUN, 1, heard)  # as if n2 heard n0's announcement
    members = await dead(nodes)
    b = RunTeam(nodes[1], RUN, members)
    async with asyncio.timeout(BOUND):
        outcome = await b.distributed_or(hold)
    assert (outcome.winner, outcome.result) == ("n2", 7)


async def test_a_successor_whose_run_ended_still_decides_for_the_others(
    nodes: list[Node],
) -> None:
    """n1's run has ended (it failed the step before, as b did in CI); n0 dies while n2 waits
    in OR step 1. n2 asks n1, now the designated member, whose own member will never join: it
    decides all the same, and n2 ends with MemberLost (it used to wait for n1's member), n1
    among the lost: its run ended before the step (it said so)."""
    b = Collectives(nodes[1])
    c = RunTeam(nodes[2], RUN, ["n0", "n1", "n2"])
    b.end_run(RUN)
    step = asyncio.ensure_future(c.distributed_or(hold))
    await dead(nodes)
    with pytest.raises(MemberLost) as lost:
        await asyncio.wait_for(step, BOUND)
    assert lost.value.members == {"n0", "n1"}
