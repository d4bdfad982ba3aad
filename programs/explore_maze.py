"""Distributed maze exploration as robot processes (Linardakis et al., CU-LVP and baselines).

Every member runs the same :class:`~robots.explore.ExplorerAgent` the in-process runner
(``experiments.maze``) uses, one per process, and the same round,
:func:`~robots.explore.explore_rounds`; this program is its driver over the grid HAL and
mover's range-limited broadcast. Per round a robot

1. reads its star sensor (view rays) and records the cells on its own map, at the cell its
   odometry says it is on (its start cell, given at launch, plus the cells it has moved);
2. broadcasts the agent's message (position, goal, regions, only the map cells that changed)
   with mover's range-limited broadcast;
3. waits for the broadcasts of this round from the members the radio medium says are in range
   (the grid world's step reply tells), so that it hears exactly what the in-process agent
   would; a member that leaves the team is not waited for;
4. if it heard anyone, relays what it heard to them and hears their relays, ``exchanges - 1``
   times (:data:`robots.explore.EXCHANGES`), waiting for each as in 3;
5. decides and moves.

The team's start cells and the maze's shape are launch data, as team membership is (the
agents derive the same Voronoi partition from them); agent ``i`` is the ``i``-th member in
name order, which is also the order in which the world applies moves. The run ends when the
world's observer says everything the robots can see has been seen: with the same maze, seed
and starts it takes exactly as many rounds as the in-process run.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Container
from contextlib import AbstractAsyncContextManager
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from mover import Message, pack
from robots import Robot
from robots.explore import (
    EXCHANGES,
    FREE,
    OBSTACLE,
    UNKNOWN,
    Exchange,
    ExplorerAgent,
    Sense,
    View,
    explore_rounds,
    make_policy,
)
from robots.grid_hal import GridHardware, direction_of

from .foraging import GridTeam, member_index, start_round

TOPIC = "maze"
#: How long a robot waits for one member's broadcast of a round before going on without it.
HEAR_TIMEOUT = 10.0


Key = tuple[int, int]  # (round, exchange within the round)


class Inbox(Protocol):
    """Messages on a topic, as a subscription gives them (a ``mover`` subscription is one)."""

    async def get(self, timeout: float | None = None) -> Message:
        """The next message (``TimeoutError`` after ``timeout`` s)."""


class MazeNode(Protocol):
    """What the maze program asks of its node: a :class:`mover.Node` is one."""

    @property
    def membership(self) -> Container[str]:
        """Who is in the team now."""

    def subscribe(self, topic: str) -> AbstractAsyncContextManager[Inbox]:
        """The messages on ``topic`` while the context is open."""

    async def broadcast(
        self, topic: str, data: Any, *, range: float | None = None, reliable: bool = False
    ) -> None:
        """Send ``data`` on ``topic`` to the members within ``range``."""


class MazeTeam(GridTeam, Protocol):
    """What the maze program asks of its team: a :class:`mover.RunTeam` is one."""

    @property
    def run(self) -> str:
        """The run's name (its broadcasts' topic)."""

    @property
    def node(self) -> MazeNode:
        """This member's node."""


async def _hear(
    node: MazeNode,
    log: logging.Logger,
    sub: Inbox,
    inbox: dict[Key, dict[str, Any]],
    round: Key,
    expected: set[str],
) -> dict[str, dict[str, Any]]:
    """The broadcasts of exchange ``round`` from ``expected``; later ones are kept for theirs."""
    got = inbox.pop(round, {})
    deadline = time.monotonic() + HEAR_TIMEOUT
    while True:
        missing = {m for m in expected - set(got) if m in node.membership}
        if not missing or time.monotonic() > deadline:
            if missing:
                log.warning("round %d: no broadcast from %s", round, sorted(missing))
            return {s: m for s, m in got.items() if s in expected}
        try:
            msg = await sub.get(timeout=0.25)
        except TimeoutError:
            continue
        k = (int(msg.data["round"]), int(msg.data["exchange"]))
        if k == round:
            got[msg.sender] = msg.data["agent"]
        elif k > round:
            inbox.setdefault(k, {})[msg.sender] = msg.data["agent"]


def map_text(agent: ExplorerAgent) -> str:
    """An agent's map as text: ``#`` obstacle, ``.`` free, ``?`` unknown, ``@`` the agent."""
    chars = {UNKNOWN: "?", FREE: ".", OBSTACLE: "#"}
    rows = [[chars.get(int(v), "?") for v in row] for row in agent.known]
    r, c = agent.position
    rows[r][c] = "@"
    return "\n".join("".join(row) for row in rows) + "\n"


async def explore_maze(
    robot: Robot[GridHardware],
    team: MazeTeam,
    method: str = "cu_lvp",
    seed: int | None = None,
    starts: list[list[int]] | None = None,
    shape: list[int] | None = None,
    max_rounds: int = 0,
    snapshot_dir: str = "",
    exchanges: int = EXCHANGES,
) -> dict[str, Any]:
    """Explore the maze with ``method`` (cu_lvp, nf, cu_mnm, cu_jgr, cu_bso, hedac).

    ``starts`` are every member's start cell in member-name order and ``shape`` the maze's
    (rows, cols). ``seed`` (default: the run's, ``team.seed``) gives agent ``i`` the ``i``-th
    child of ``SeedSequence(seed)``, as the in-process ``make_team`` does. With ``snapshot_dir``
    the robot writes its map there (``<robot>.txt``) at the end. Returns rounds, cells moved,
    message bytes sent (msgpack), cells known. ``exchanges`` is the number of map exchanges per
    round (1: the paper's).
    """
    if not starts or not shape:
        raise ValueError("starts and shape are needed (launch data: the team's start cells)")
    hw, node = robot.hw, team.node
    n = len(team.members)
    if len(starts) != n:
        raise ValueError(f"{len(starts)} starts for {n} members")
    i = member_index(robot, team)
    cells = [(int(r), int(c)) for r, c in starts]
    seed = team.seed if seed is None else seed
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(n)[i])
    agent = ExplorerAgent(
        i, (int(shape[0]), int(shape[1])), cells, make_policy(method.replace("_", "-")), rng
    )
    radio = hw.radio
    assert radio is not None, "maze exploration needs a radio"
    reach = radio.range + 2  # the medium decides who hears; moving one cell must not lose it
    topic = f"{TOPIC}/{team.run}"
    rounds = moves = sent = 0
    inbox: dict[Key, dict[str, Any]] = {}
    plan = explore_rounds(agent, exchanges)

    async def send(data: dict[str, Any]) -> int:
        """Broadcast to the members in radio range; the bytes of the agent's message."""
        await node.broadcast(
            topic, data, range=reach if reach != float("inf") else None, reliable=True
        )
        return len(pack(data["agent"]))

    # subscribed before the start step: no member broadcasts before every one listens
    async with node.subscribe(topic) as sub, hw.clock.owned(at=await start_round(hw, team)):
        hearers: set[str] = set()
        now = 0
        request = next(plan)
        while True:
            reply: Any = None
            if isinstance(request, Sense):
                dr, dc, _ = hw.odometry.pose()
                r, c = cells[i][0] + int(dr), cells[i][1] + int(dc)
                seen = [(r + s.d_row, c + s.d_col, int(s.obstacle)) for s in hw.senses.rays()]
                over = hw.clock.ended() or bool(max_rounds and rounds >= max_rounds)
                reply = View(seen, (r, c), over)
            elif isinstance(request, Exchange):
                k = request.index
                if k == 0:
                    now = hw.clock.now()
                sent += await send({"round": now, "exchange": k, "agent": request.message})
                if k == 0:
                    hearers = set(radio.in_range())
                heard = await _hear(node, robot.log, sub, inbox, (now, k), hearers)
                reply = sorted(heard.values(), key=lambda m: m["id"])
            else:
                hw.drive.move(direction_of(*request.move))
                await hw.clock.tick()
                moves += hw.drive.moved()
                rounds += 1
            try:
                request = plan.send(reply)
            except StopIteration:
                break
    if snapshot_dir:
        path = Path(snapshot_dir) / f"{robot.id}.txt"
        path.parent.mkdir(parents=True, exist_ok=True)
        await asyncio.to_thread(path.write_text, map_text(agent))
    return {
        "rounds": rounds,
        "moves": moves,
        "index": i,
        "sent_bytes": sent,
        "known": int(np.count_nonzero(agent.known != UNKNOWN)),
        "finished": hw.clock.ended(),
    }
