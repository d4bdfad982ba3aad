"""distributed_or / distributed_and among nodes in one process (real zenoh on 127.0.0.1)."""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Awaitable, Callable

import pytest

from mover import Node, OperationFailed, RunTeam
from tests.helpers.steps import after_a_loss


def teams(nodes: list[Node], run: str = "r", **kw: object) -> list[RunTeam]:
    names = [n.name for n in nodes]
    return [RunTeam(n, run, names, **kw) for n in nodes]  # type: ignore[arg-type]


async def test_or_first_finisher_wins_and_losers_clean_up(nodes: list[Node]) -> None:
    cleaned: list[str] = []

    def op(name: str, delay: float) -> Callable[[], Awaitable[str]]:
        async def run() -> str:
            try:
                await asyncio.sleep(delay)
                return f"found by {name}"
            finally:
                cleaned.append(name)

        return run

    ts = teams(nodes)
    delays = {"n0": 5.0, "n1": 5.0, "n2": 0.05, "n3": 5.0, "n4": 5.0}
    outs = await asyncio.gather(*(t.distributed_or(op(t.me, delays[t.me])) for t in ts))
    assert {(o.winner, o.result) for o in outs} == {("n2", "found by n2")}
    assert sorted(cleaned) == ["n0", "n1", "n2", "n3", "n4"]  # every operation ended
    total = sum(t.metrics[0].messages for t in ts)
    assert total == len(nodes) + 1  # a claim and its reply, the announcement to n-1 others


async def test_or_ties_agree(nodes: list[Node]) -> None:
    ts = teams(nodes)
    for _ in range(20):

        async def now(t: RunTeam) -> str:
            return t.me

        outs = await asyncio.gather(*(t.distributed_or(functools.partial(now, t)) for t in ts))
        assert len({o.winner for o in outs}) == 1


async def test_and_gives_everyone_all_results_both_variants(nodes: list[Node]) -> None:
    ts = teams(nodes)
    for designated in (True, False):

        async def op(t: RunTeam) -> int:
            await asyncio.sleep(0.01 * int(t.me[1:]))
            return int(t.me[1:]) ** 2

        outs = await asyncio.gather(
            *(t.distributed_and(functools.partial(op, t), designated=designated) for t in ts)
        )
        assert all(o == {f"n{i}": i * i for i in range(5)} for o in outs)
    n = len(nodes)
    designated_msgs = sum(t.metrics[0].messages for t in ts)
    all_msgs = sum(t.metrics[1].messages for t in ts)
    assert designated_msgs == 2 * (n - 1)
    assert all_msgs == 2 * n * (n - 1)


async def test_and_reports_failed_operations(nodes: list[Node]) -> None:
    ts = teams(nodes)

    async def op(t: RunTeam) -> str:
        if t.me == "n3":
            raise RuntimeError("stuck")
        return "ok"

    outs = await asyncio.gather(
        *(t.distributed_and(functools.partial(op, t)) for t in ts), return_exceptions=True
    )
    assert isinstance(outs[3], RuntimeError)
    assert outs[0]["n3"] == OperationFailed("RuntimeError", "stuck")  # type: ignore[index]


async def test_continuation_gets_the_outcome(nodes: list[Node]) -> None:
    ts = teams(nodes)

    async def op(t: RunTeam) -> int:
        await asyncio.sleep(0 if t.me == "n4" else 5)
        return 7

    async def then(outcome: object) -> str:
        return f"continued after {outcome.winner}"  # type: ignore[attr-defined]

    outs = await asyncio.gather(*(t.distributed_or(functools.partial(op, t), then) for t in ts))
    assert outs == ["continued after n4"] * 5


@pytest.mark.parametrize("policy", ["fail", "survivors"])
async def test_a_member_leaving_during_and_fails_the_step_or_is_survived(
    nodes: list[Node], policy: str
) -> None:
    ts = teams(nodes[:4], policy=policy)

    async def op(t: RunTeam) -> str:
        await asyncio.sleep(3600 if t.me == "n3" else 0.01)  # n3 never finishes
        return t.me

    tasks = [asyncio.ensure_future(t.distributed_and(functools.partial(op, t))) for t in ts]
    await asyncio.sleep(0.2)
    tasks[3].cancel()
    await nodes[3].close()  # as if n3's process died
    outs = await after_a_loss(policy, tasks[:3], 1.0)
    if policy != "fail":
        assert outs == [{"n0": "n0", "n1": "n1", "n2": "n2"}] * 3


async def test_a_run_of_its_own_policy_survives_on_a_node_that_fails_by_default(
    nodes: list[Node],
) -> None:
    ts = teams(nodes[:3], run="own")  # the nodes' default policy: fail
    for t in ts:
        t.collectives.set_policy("own", "survivors")  # as mover.start sets a launch's policy

    async def op(t: RunTeam) -> str:
        await asyncio.sleep(3600 if t.me == "n2" else 0.01)
        return t.me

    tasks = [asyncio.ensure_future(t.distributed_and(functools.partial(op, t))) for t in ts]
    await asyncio.sleep(0.2)
    tasks[2].cancel()
    await nodes[2].close()
    outs = [await asyncio.wait_for(task, 1.0) for task in tasks[:2]]
    assert outs == [{"n0": "n0", "n1": "n1"}] * 2


async def test_a_long_or_step_costs_2n_messages(nodes: list[Node]) -> None:
    """Members that ask for the decision get it in the answer: no announcement is sent."""
    ts = teams(nodes)

    async def op(t: RunTeam) -> str:
        await asyncio.sleep(0.5 if t.me == "n3" else 5.0)  # longer than POLL_AFTER
        return t.me

    outs = await asyncio.gather(*(t.distributed_or(functools.partial(op, t)) for t in ts))
    assert {o.winner for o in outs} == {"n3"}
    total = sum(t.metrics[0].messages for t in ts)
    assert total == 2 * len(nodes)  # n-1 polls and answers, the claim and its answer


async def test_a_designated_member_without_collectives_fails_the_step_clearly(
    nodes: list[Node],
) -> None:
    """An answered error (here UnknownProcedure) is not retried: the step fails at once."""
    from mover import UnknownProcedure

    plain, member = nodes[0], nodes[1]  # the first by name is designated, and serves nothing
    team = RunTeam(member, "r", [plain.name, member.name])
    before = plain.stats["recv.call"]

    async def op() -> str:
        return "done"

    with pytest.raises(UnknownProcedure, match=r"mover\.or_claim"):
        await asyncio.wait_for(team.distributed_or(op), 10)
    assert plain.stats["recv.call"] - before <= 2  # a claim (and a poll), never a spin


async def test_a_malformed_decision_leaves_every_listener_alive(nodes: list[Node]) -> None:
    from mover._collective._step import DECIDED_TOPIC

    members, sender = nodes[:4], nodes[4]
    ts = teams(members)
    await asyncio.sleep(0.2)  # the listeners' subscriptions reach the sender
    bad: object
    for bad in (["r", "1", []], ["r", 1.5, []], [1, 1, []], ["r", 1, "x"], "junk", None, {}):
        sender.broadcast_nowait(DECIDED_TOPIC, bad, reliable=True)
    await asyncio.sleep(0.3)
    assert all(not t.collectives._listener.done() for t in ts)

    async def op() -> str:
        await asyncio.sleep(0.05)
        return "ok"

    outcomes = await asyncio.wait_for(asyncio.gather(*(t.distributed_or(op) for t in ts)), 10)
    assert len({o.winner for o in outcomes}) == 1
    assert all(not t.collectives._listener.done() for t in ts)


async def test_steps_that_are_never_decided_stay_bounded(nodes: list[Node]) -> None:
    """A member that opens 2,000 OR steps and never decides one: the designated member keeps
    at most its step memory of them (their waiters are told), not 2,000 tasks."""
    from mover import RemoteError
    from mover._collective import Collectives
    from mover._collective._step import STEP_MEMORY

    designated, rogue = nodes[0], nodes[1]
    collectives = Collectives(designated)
    members = [designated.name, rogue.name]
    calls = [
        asyncio.ensure_future(
            rogue.call(designated.name, "mover.or_join", "r", k, rogue.name, members, timeout=20)
        )
        for k in range(2000)
    ]
    async with asyncio.timeout(20):
        while designated.stats["recv.call"] < 2000:
            await asyncio.sleep(0.05)
    await asyncio.sleep(0.2)
    assert len(collectives._steps) <= STEP_MEMORY
    assert len(designated._server.tasks) <= STEP_MEMORY + 10
    dropped = await asyncio.gather(*calls[: 2000 - STEP_MEMORY], return_exceptions=True)
    assert all(isinstance(e, RemoteError) and "never decided" in str(e) for e in dropped)
    for call in calls:
        call.cancel()
    await asyncio.gather(*calls, return_exceptions=True)


async def test_a_successor_that_heard_the_decision_hands_it_on(nodes: list[Node]) -> None:
    """The designated member (n0) announced, then died; a member that missed the announcement
    asks the successor (n1), which heard it and moved on: it answers at once, the same."""
    from mover._collective import Collectives, Decision

    n0, n1, n2 = nodes[:3]
    members = [n.name for n in nodes]
    successor = Collectives(n1)
    heard = Decision("won", winner="n3", result=7)
    successor.learned("r", 1, heard)  # as if its listener heard n0's broadcast
    await n0.close()
    await n1.membership.wait_gone("n0", timeout=10)
    await n2.membership.wait_gone("n0", timeout=10)
    answer = await n2.call("n1", "mover.or_join", "r", 1, "n2", members, timeout=3)
    assert Decision.from_wire(answer) == heard


@pytest.mark.parametrize("successor_learns", ["heard", "asked"])
async def test_the_designated_member_killed_right_after_it_announced(
    nodes: list[Node], successor_learns: str
) -> None:
    """n0 (the designated member) wins an OR, announces, and is gone at once. Its successor n1
    learned the decision (from the announcement, or, having started the step late, by asking
    n0) and moved on; n2, which had not started the step yet (it missed the announcement), asks
    n1, now the designated member: n1 hands on the decision it learned, and n2 agrees on n0
    without n1 ever joining its own takeover step."""
    n0, n1, n2 = nodes[:3]
    members = [n0.name, n1.name, n2.name]

    async def at_once() -> str:
        return "n0's"

    async def long() -> str:
        await asyncio.sleep(30)
        return "late"

    t0 = RunTeam(n0, "r", members)
    if successor_learns == "heard":
        t1 = RunTeam(n1, "r", members)
        first, second = await asyncio.gather(
            t0.distributed_or(at_once), asyncio.wait_for(t1.distributed_or(long), 10)
        )
    else:
        first = await t0.distributed_or(at_once)
        t1 = RunTeam(n1, "r", members)  # too late to hear the announcement: it asks n0
        second = await asyncio.wait_for(t1.distributed_or(long), 10)
    assert first.winner == second.winner == "n0"
    await n0.close()  # right after its announcement
    await n1.membership.wait_gone("n0", timeout=10)
    await n2.membership.wait_gone("n0", timeout=10)
    t2 = RunTeam(n2, "r", members)  # its listener starts now: the announcement is past
    late = await asyncio.wait_for(t2.distributed_or(long), 10)
    assert (late.winner, late.result) == ("n0", "n0's")


def test_a_member_counted_lost_is_told_that_it_was() -> None:
    from mover._collective import Decision

    lost = Decision("lost", lost=("moseley",))
    assert lost.lost_message("rescue", 1, "ernst") == "step 1 of run 'rescue' lost ['moseley']"
    told = lost.lost_message("rescue", 1, "moseley")
    assert told.startswith("step 1 of run 'rescue' lost ['moseley']: this member (moseley)")
    assert "past its lease" in told
