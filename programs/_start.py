"""The common start of the programs that run in simulated time: the team agrees on a time a
little after the latest any member has seen, so that every robot starts deciding at the same
tick."""

from __future__ import annotations

from mover import RunTeam
from robots.hal import Clock

#: Ticks between the latest member's tick when the team agreed and the common start.
START_LEAD = 20


async def common_start(clock: Clock, team: RunTeam, lead: int = START_LEAD) -> float:
    """Agree with the team on the simulated time at which everyone starts, ``lead`` ticks after
    the latest time any member has seen (one ``and`` step); tick until then and return it."""

    async def now() -> float:
        return clock.now()

    latest = max(float(t) for t in (await team.distributed_and(now)).values())
    start = latest + lead * clock.tick_period
    while clock.now() < start - 1e-9:
        await clock.tick()
    return clock.now()
