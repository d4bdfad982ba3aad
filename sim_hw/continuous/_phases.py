"""The program phase of each robot, for a world's recording: what the robots' programs report
(:meth:`mover.RunTeam.report`) heard by the world process.

A world does not run programs and a run's reports go to ``mover/run/RUN``, a topic per run, so
:func:`watch_phases` asks each robot on the world for its runs (``mover.status``) every
:data:`POLL` seconds, records the phase it says, and listens to each run's progress topic from
then on (so a phase that begins and ends between two polls is still heard once its run is
known). Each phase is handed to ``record(member, phase)``; the recorder writes it with the next
recorded tick.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Collection
from typing import Any

from mover import PROGRESS_TOPIC, MoverError, Node

log = logging.getLogger("sim_hw.phases")

POLL = 0.5
"""Seconds between two asks of the robots for their runs."""
DRAIN = 0.05
"""Seconds between two looks at the progress topics."""


async def watch_phases(
    node: Node, robots: Callable[[], Collection[str]], record: Callable[[str, str], None]
) -> None:
    """Hand every phase the members ``robots()`` report to ``record`` until cancelled."""
    subs: dict[str, Any] = {}
    last: dict[str, str] = {}

    def note(member: str, phase: Any) -> None:
        if isinstance(phase, str) and last.get(member) != phase:
            last[member] = phase
            record(member, phase)

    async def status(member: str) -> None:
        try:
            runs = await node.call(member, "mover.status", timeout=POLL)
        except MoverError:
            return  # not up yet, or not a program host
        for run in runs if isinstance(runs, list) else ():
            name = run.get("run") if isinstance(run, dict) else None
            if not isinstance(name, str) or name in subs:
                continue
            subs[name] = node.subscribe(f"{PROGRESS_TOPIC}/{name}")
            note(member, run.get("phase"))

    try:
        while True:
            asking = asyncio.ensure_future(asyncio.gather(*map(status, sorted(robots()))))
            while not asking.done():
                await asyncio.sleep(DRAIN)
                _drain(subs, note)
            for _ in range(round(POLL / DRAIN)):
                _drain(subs, note)
                await asyncio.sleep(DRAIN)
    finally:
        for sub in subs.values():
            sub.close()


def _drain(subs: dict[str, Any], note: Callable[[str, Any], None]) -> None:
    for sub in subs.values():
        for m in sub.drain():
            data = m.data if isinstance(m.data, dict) else {}
            note(str(data.get("member", m.sender)), data.get("phase"))
