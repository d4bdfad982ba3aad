"""A team member for tests/mover/test_step_liveness.py: one step, with its victim announcing its
phase on standard output (``PHASE <run> <phase>``) at the moment the test signals it.

``python -m tests.helpers.step_member --name NAME``; team and zenoh settings from MOVER_*.

The program ``step(kind, victim, phase)`` runs one ``distributed_and`` or ``distributed_or``
(``kind``) and then a barrier (an AND), so that a member that got through the step meets the
loss there. The members other than ``victim`` hold in their operation until the step ends
(except in phase ``deciding``, where an AND's members all finish); the victim, by ``phase``:

``before``    announces, then never enters the step
``enter``     announces as its operation starts (the step has just begun), then holds
``inside``    holds in its operation for a moment, announces, then holds
``after``     announces as its operation ends (an OR's raises: it never claims)
``won``       (an OR; the victim must not be the designated member) finishes at once, claims
              and wins; announces as its claim is answered (the step decided on the
              designated member, which tells the others), then holds before the barrier
``deciding``  finishes at once; as the decision is taken on the designated member (the victim
              must be it), announces and blocks its loop for a moment: the decision has not
              left yet
``stop``      (the test SIGSTOPs it) holds in its operation, as ``inside``
``raises``    finishes at once and gets through the step; then announces, and its program
              raises (its process lives on): the others wait for it at the barrier

With ``hold`` (seconds) the other members finish their operation then (0: a run with no
victim, or members that reach the step after the victim is lost).

Each member ends with ``ok <time>`` or raises; the test reads ``mover.outcome``.

SIGTERM ends the process as Ctrl-C does (its runs cancelled, every ``finally`` run, exit status
143), as it ends ``mover robot`` and ``python -m robots`` (``mover.cli.interrupt_on_sigterm``).
"""

from __future__ import annotations

import argparse
import asyncio
import faulthandler
import logging
import signal
import sys
import time
from collections.abc import Callable
from typing import Any

from mover import RunTeam
from mover._collective import Collectives
from mover.cli import Terminated, interrupt_on_sigterm
from mover.testing import serve_programs

HOLD = 3600.0  # an operation that never ends by itself


def announce(team: RunTeam, phase: str) -> None:
    print(f"PHASE {team.run} {phase}", flush=True)


def hook_decisions(team: RunTeam) -> None:
    """Announce as this (designated) member decides a step of the run, before it is told."""
    collectives = team.collectives
    assert isinstance(collectives, Collectives)
    decide = collectives._decide  # the one writer of a step's decision

    def deciding(state: Any, decision: Any) -> None:
        if state.run == team.run and state.step > 0 and state.served:
            announce(team, "deciding")
            time.sleep(0.3)  # the loop stands still: the decision has not left this process
        decide(state, decision)

    collectives._decide = deciding  # type: ignore[method-assign]


async def step(
    robot: None, team: RunTeam, kind: str, victim: str, phase: str, hold: float = HOLD
) -> str:
    """One step of ``kind`` ("and" or "or") and a barrier; see the module's docstring. The
    other members finish their operation after ``hold`` seconds."""
    me_victim = team.me == victim
    if me_victim and phase == "deciding":
        hook_decisions(team)

    async def operation() -> str:
        if not me_victim:
            if not (phase == "deciding" and kind == "and"):
                await asyncio.sleep(hold)
            return team.me
        if phase == "enter":
            announce(team, "enter")
        elif phase in ("inside", "stop"):
            await asyncio.sleep(0.3)
            announce(team, phase)
        elif phase == "after":
            announce(team, "after")
            if kind == "or":
                raise RuntimeError("the victim's operation fails: it never claims")
            return team.me
        elif phase in ("deciding", "raises", "won"):
            return team.me
        await asyncio.sleep(HOLD)
        return team.me

    if me_victim and phase == "before":
        announce(team, "before")
        await asyncio.sleep(HOLD)
    if kind == "or":
        outcome = await team.distributed_or(operation)
        if me_victim and phase == "won":
            assert outcome.winner == team.me, outcome  # the others hold: it wins
            announce(team, "won")
            await asyncio.sleep(HOLD)
    else:
        await team.distributed_and(operation)
    if me_victim and phase == "raises":
        announce(team, "raises")
        raise RuntimeError("the victim's program raises between steps")
    await team.distributed_and(lambda: asyncio.sleep(0))
    return f"ok {time.time()}"


PROGRAMS: dict[str, Callable[..., Any]] = {"step": step}


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--name", required=True)
    logging.basicConfig(level=logging.WARNING, format="%(name)s %(levelname)s %(message)s")
    name = p.parse_args().name
    # SIGINT is Ctrl-C even when the tests run in a shell's background job, whose processes
    # inherit SIGINT ignored (then a SIGINT case would test nothing, and time out).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    interrupt_on_sigterm()  # as the robot processes do
    faulthandler.register(signal.SIGUSR1, all_threads=True)  # a test's look at a hung member
    try:
        asyncio.run(serve_programs(name, PROGRAMS, timeout=20))
    except Terminated:
        sys.exit(143)
    except KeyboardInterrupt:
        sys.exit(130)
