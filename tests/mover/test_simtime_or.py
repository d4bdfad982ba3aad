"""distributed_or in simulated time: nodes in one process (real zenoh on 127.0.0.1) and a fake
lock-step world whose ticks advance only when every engaged member has handed in its command."""

from __future__ import annotations

import asyncio
import math
import random
import time
from collections.abc import Awaitable, Callable, Mapping

import pytest

from mover import Node, Outcome, RunTeam
from tests.helpers.clocks import UnmodelledHold
from tests.helpers.steps import after_a_loss

DT = 0.1  # simulated seconds per tick


class FakeWorld:
    """Lock-step: a tick advances when every engaged member has handed in its command; a world
    whose members are all released holds still."""

    def __init__(self) -> None:
        self.tick = 0
        self.engaged: set[str] = set()
        self.handed: set[str] = set()
        self._changed = asyncio.Event()

    @property
    def time(self) -> float:
        return round(self.tick * DT, 9)

    def notify(self) -> None:
        if self.engaged and self.engaged <= self.handed:
            self.tick += 1
            self.handed.clear()
        self._changed.set()
        self._changed = asyncio.Event()

    async def wait(self) -> None:
        await self._changed.wait()

    def drop(self, name: str) -> None:
        """The member's process left: the world stops waiting for it."""
        self.engaged.discard(name)
        self.notify()


class FakeClock(UnmodelledHold):
    """A member's :class:`mover.RunClock` over the fake world, with ``tick`` for its operation."""

    def __init__(self, world: FakeWorld, name: str) -> None:
        self.world, self.name = world, name
        self._now = world.time
        self.handed_at = -math.inf  # the time of the readings it last handed a command in on

    def now(self) -> float:
        return self._now

    async def tick(self) -> None:
        w = self.world
        tick = w.tick
        self.world.engaged.add(self.name)  # a robot that commands is not idle
        self.handed_at = w.time
        w.handed.add(self.name)
        w.notify()
        await asyncio.sleep(0)  # a tick is never instant (the last to hand one in spins else)
        while w.tick == tick:
            await w.wait()
        self._now = w.time

    async def passed(self, t: float) -> None:
        while not self.handed_at >= t:  # it went on from readings of t (robots.hal.Clock)
            await self.world.wait()

    async def engage(self) -> None:
        self.world.engaged.add(self.name)

    def release(self) -> None:
        self.world.engaged.discard(self.name)
        self.world.notify()


def timed_teams(
    nodes: list[Node], world: FakeWorld, run: str, *, clocks: bool = True, **kw: object
) -> tuple[list[RunTeam], dict[str, FakeClock]]:
    names = [n.name for n in nodes]
    fake = {n.name: FakeClock(world, n.name) for n in nodes}
    world.engaged = set(names)  # every run engages its clock before it begins
    teams = [
        RunTeam(n, run, names, clock=fake[n.name] if clocks else None, **kw)  # type: ignore[arg-type]
        for n in nodes
    ]
    return teams, fake


def walker(
    clock: FakeClock,
    until: float,
    *,
    wall_after: float = 0.0,
    jitter: random.Random | None = None,
    returned: dict[str, float] | None = None,
) -> Callable[[], Awaitable[str]]:
    """An operation that ticks until simulated time ``until``, then stops holding the world (a
    finished robot waits idle), spends ``wall_after`` wall seconds, and returns its name."""

    async def op() -> str:
        try:
            while clock.now() < until - 1e-9:
                if jitter is not None:
                    await asyncio.sleep(jitter.uniform(0.0, 0.003))
                await clock.tick()
            clock.release()
            await asyncio.sleep(wall_after)
            if returned is not None:
                returned[clock.name] = time.perf_counter()
            return clock.name
        finally:
            clock.release()

    return op


async def run_or(
    teams: list[RunTeam], ops: Mapping[str, Callable[[], Awaitable[str]]]
) -> list[Outcome]:
    return await asyncio.wait_for(
        asyncio.gather(*(t.distributed_or(ops[t.me]) for t in teams)),
        20,
    )


async def test_the_first_in_simulated_time_wins_though_its_claim_comes_last(
    nodes: list[Node],
) -> None:
    """n3 finishes at 0.5 s but returns 0.5 wall seconds later; n1 finishes at 0.8 s and
    claims first in wall time. n3 wins in simulated time; the wall-clock rule picks n1."""
    for clocks, expected in ((True, "n3"), (False, "n1")):
        world = FakeWorld()
        teams, fake = timed_teams(nodes, world, f"late-{clocks}", clocks=clocks)
        returned: dict[str, float] = {}
        ends = {"n1": 0.8, "n3": 0.5}
        ops = {
            name: walker(
                clock,
                ends.get(name, 1e9),
                wall_after=0.5 if name == "n3" else 0.0,
                returned=returned,
            )
            for name, clock in fake.items()
        }
        outs = await run_or(teams, ops)
        assert {o.winner for o in outs} == {expected}
        assert returned["n1"] < returned.get("n3", math.inf)  # n1 was first in wall time


async def test_the_winner_does_not_depend_on_wall_clock_jitter(nodes: list[Node]) -> None:
    """Every member ends at its own simulated time, ticking with random wall delays: three
    runs, three different wall orders, one winner (the earliest in simulated time)."""
    ends = {"n0": 1.2, "n1": 0.9, "n2": 1.0, "n3": 0.7, "n4": 0.8}
    winners = []
    for trial in range(3):
        world = FakeWorld()
        teams, fake = timed_teams(nodes, world, f"jitter{trial}")
        rng = random.Random(trial)
        ops = {
            name: walker(clock, ends[name], wall_after=rng.uniform(0, 0.3), jitter=rng)
            for name, clock in fake.items()
        }
        outs = await run_or(teams, ops)
        assert len({o.winner for o in outs}) == 1
        winners.append(outs[0].winner)
    assert winners == ["n3"] * 3


async def test_a_tie_in_simulated_time_goes_to_the_first_by_name(nodes: list[Node]) -> None:
    """n2 and n4 both finish at 0.5 s; n4 returns (and claims) first in wall time."""
    world = FakeWorld()
    teams, fake = timed_teams(nodes, world, "tie")
    returned: dict[str, float] = {}
    ops = {
        name: walker(
            clock,
            0.5 if name in ("n2", "n4") else 1e9,
            wall_after=0.3 if name == "n2" else 0.0,
            returned=returned,
        )
        for name, clock in fake.items()
    }
    outs = await run_or(teams, ops)
    assert {o.winner for o in outs} == {"n2"}
    assert returned["n4"] < returned["n2"]


async def test_a_short_simulated_step_costs_3_n_minus_3_messages(
    nodes: list[Node], monkeypatch: pytest.MonkeyPatch
) -> None:
    """One claim and its answer, n-2 questions and answers (the designated member asks itself
    for free), n-1 deliveries of the announcement."""
    # short however loaded the machine is
    monkeypatch.setattr("mover._collective._member.POLL_AFTER", 10.0)
    world = FakeWorld()
    teams, fake = timed_teams(nodes, world, "cost")
    ops = {name: walker(clock, 0.3 if name == "n2" else 1e9) for name, clock in fake.items()}
    outs = await run_or(teams, ops)
    assert {o.winner for o in outs} == {"n2"}
    n = len(nodes)
    assert sum(t.metrics[0].messages for t in teams) == 3 * (n - 1)


@pytest.mark.parametrize("policy", ["fail", "survivors"])
async def test_a_member_leaving_while_the_others_wait_for_it(
    nodes: list[Node], policy: str
) -> None:
    """n1 claims at 0.1 s; n4 hangs at 0.1 s holding the world, so nobody can go past 0.1 s,
    then n4's process dies: the step ends within the usual bound (MemberLost, or n1 wins)."""
    world = FakeWorld()
    teams, fake = timed_teams(nodes[:5], world, f"leave-{policy}", policy=policy)

    async def hang() -> str:
        await fake["n4"].tick()
        await asyncio.sleep(3600)  # holding the world: engaged, no command
        return "n4"

    ops = {name: walker(clock, 0.1 if name == "n1" else 1e9) for name, clock in fake.items()}
    ops["n4"] = hang
    tasks = [asyncio.ensure_future(t.distributed_or(ops[t.me])) for t in teams]
    await asyncio.sleep(0.5)
    assert not any(t.done() for t in tasks)  # waiting for n4 to go past 0.1 s
    assert world.time == pytest.approx(0.1)
    tasks[4].cancel()
    await nodes[4].close()  # as if n4's process died
    world.drop("n4")
    t0 = time.monotonic()
    outs = await after_a_loss(policy, tasks[:4], 2.0)
    if policy != "fail":
        assert {o.winner for o in outs} == {"n1"}
    assert time.monotonic() - t0 < 2.0
    await asyncio.gather(*tasks, return_exceptions=True)


async def test_the_designated_members_questions_end_with_their_owner(nodes: list[Node]) -> None:
    """The designated member's ``or_passed`` questions are tasks of one TaskGroup (its
    Collectives' listener), not bare tasks: ending the owner ends every question still asked.
    n2 claims at 0.2 s; n1 idles without ever going past it, so its question stays open."""
    world = FakeWorld()
    teams, fake = timed_teams(nodes, world, "owned")
    stuck = asyncio.Event()

    async def idle() -> str:
        fake["n1"].release()  # the world goes on without it; it never hands in a command
        await stuck.wait()
        return "n1"

    ops = {name: walker(clock, 0.2 if name == "n2" else 1e9) for name, clock in fake.items()}
    ops["n1"] = idle
    steps = [asyncio.ensure_future(t.distributed_or(ops[t.me])) for t in teams]
    designated = teams[0].collectives
    async with asyncio.timeout(10):
        while not (asked := [q for s in designated._steps.values() for q in s.asking.values()]):
            await asyncio.sleep(0.02)
    await asyncio.sleep(0.2)
    assert not any(step.done() for step in steps)  # waiting for n1's answer
    designated._listener.cancel()
    await asyncio.gather(designated._listener, return_exceptions=True)
    assert all(q.done() for q in asked)
    for step in steps:
        step.cancel()
    await asyncio.gather(*steps, return_exceptions=True)
