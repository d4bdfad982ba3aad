"""One agent's rounds, written once: sense, exchange and relay, decide, move.

Linardakis et al., section III: every round an agent reads its star sensor, broadcasts what
changed to the agents within range and hears theirs, passes on what it heard (the relays of
:data:`EXCHANGES`, only if it heard anyone), decides, and moves. :func:`explore_rounds` is that
loop for one :class:`ExplorerAgent`, with no I/O in it: a generator that yields what it needs
done (:class:`Sense`, :class:`Exchange`, :class:`Drive`) and is sent back what came of it.

Two drivers run it. The in-process runner (``experiments.maze``) resumes every agent's
generator phase by phase over a simulated world (all sense, all exchange, all move in agent
order); the robot program (``programs.explore_maze``) resumes one over the grid HAL and mover's
range-limited broadcast. Neither writes out the round again, so a distributed run repeats an
in-process one round for round. The cost is one generator resumption per phase, well under a
microsecond beside the agent's own decision.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass
from typing import Any

from ._agent import EXCHANGES, ExplorerAgent, Move


@dataclass(frozen=True, slots=True)
class Sense:
    """Read the star sensor. Send back a :class:`View`."""


@dataclass(frozen=True, slots=True)
class View:
    """What the star sensor saw this round, where the agent stands, and whether the run ends.

    ``over``: the run ends with this view (every observable cell is known, or the clock or the
    round budget ran out); the agent records the view and its rounds are done.
    """

    cells: list[tuple[int, int, int]]  # (row, col, value), the agent's own cell included
    position: tuple[int, int]
    over: bool = False


@dataclass(frozen=True, slots=True)
class Exchange:
    """Broadcast ``message`` to the agents in range and hear theirs.

    ``index`` 0 is the round's message (position, goal, regions, changed cells), which an agent
    sends even with nobody in range; 1 and on are the relays, among the agents heard in
    exchange 0. Send back the messages heard in this exchange, in sender-id order.
    """

    index: int
    message: dict[str, Any]


@dataclass(frozen=True, slots=True)
class Drive:
    """Make ``move`` (a one-cell step, or ``STAY``). Send back None; the next round follows."""

    move: Move


Request = Sense | Exchange | Drive
#: Yields requests, is sent their replies, returns the number of rounds it moved in.
Rounds = Generator[Request, Any, int]


def explore_rounds(agent: ExplorerAgent, exchanges: int = EXCHANGES) -> Rounds:
    """The rounds of ``agent`` with ``exchanges`` map exchanges per round (1: the paper's).

    Start it with ``next()`` (it asks to :class:`Sense`), then ``send()`` each reply; it
    returns (``StopIteration.value``) once sent a :class:`View` that is ``over``.
    """
    if exchanges < 1:
        raise ValueError(f"exchanges must be at least 1, not {exchanges}")
    return _rounds(agent, exchanges)


def _rounds(agent: ExplorerAgent, exchanges: int) -> Rounds:
    made = 0
    while True:
        view: View = yield Sense()
        agent.observe(seen_cells=view.cells, position=view.position)  # 1. sense
        if view.over:
            return made
        heard = yield Exchange(0, agent.outgoing_message())  # 2. broadcast, hear
        agent.observe(heard_messages=heard)
        if heard:  # 3. relay what was heard, to the same agents
            for k in range(1, exchanges):
                agent.hear_relay((yield Exchange(k, agent.relay_message())))
        yield Drive(agent.decide())  # 4. decide, move
        made += 1
