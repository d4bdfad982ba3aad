"""Distributed maze exploration: CU-LVP and its baselines (Linardakis et al.).

Each agent is an :class:`ExplorerAgent` (its own map, region, and what it heard) with a
:class:`Policy` that turns that knowledge into a move. The same objects run in-process
(``experiments.maze``) and, one per process, on a grid world:
``observe(seen_cells, heard_messages)``, ``outgoing_message()`` (msgpack-able), the relays
``relay_message()`` / ``hear_relay()`` (see :data:`EXCHANGES`), ``decide()``. Both run them
with the same round, :func:`explore_rounds` (sense, exchange and relay, decide, move), which
asks its driver for a :class:`Sense`, an :class:`Exchange` or a :class:`Drive` at a time.
"""

from __future__ import annotations

import numpy as np

from ._agent import EXCHANGES, STAY, ExplorerAgent, Move, Peer, Policy
from ._frontier import CULVP, CostUtilityBSO, CostUtilityJGR, CostUtilityMNM, NearestFrontier
from ._grid import AGENT, FREE, OBSTACLE, UNKNOWN
from ._hedac import Hedac, attracting_field
from ._rounds import Drive, Exchange, Request, Rounds, Sense, View, explore_rounds
from ._sensing import unexplored_in_view
from ._voronoi import voronoi_partition

#: Method name -> policy factory, in the order the paper lists them.
METHODS = {
    "cu-lvp": CULVP,
    "nf": NearestFrontier,
    "cu-mnm": CostUtilityMNM,
    "cu-jgr": CostUtilityJGR,
    "cu-bso": CostUtilityBSO,
    "hedac": Hedac,
}


PARTITIONS = ("balanced", "voronoi")
"""CU-LVP's regions: of about equal size (the default), or the plain Voronoi partition."""
NEWS = ("on", "whole", "off")
"""How CU-LVP's agents pass on each other's news (see :func:`make_policy`)."""


def make_policy(method: str, partition: str = "balanced", news: str = "on") -> Policy:
    """A fresh policy for ``method`` (one of :data:`METHODS`) with the paper's parameters;
    ``partition`` (one of :data:`PARTITIONS`) sets CU-LVP's regions (the baselines': plain).
    ``news`` (one of :data:`NEWS`), how CU-LVP's agents pass on each other's news: ``"on"``
    what changed since the agent's last message (all of it to a newcomer), ``"whole"`` all of
    it in every message (as before 2026-12-04 15:30 UTC), ``"off"`` none (and helpers neither
    share a region's work by it nor choose their region again: CU-LVP before 2026-12-04)."""
    if partition not in PARTITIONS:
        raise ValueError(f"unknown partition {partition!r}; choose from {', '.join(PARTITIONS)}")
    if news not in NEWS:
        raise ValueError(f"unknown news {news!r}; choose from {', '.join(NEWS)}")
    try:
        policy = METHODS[method]()
    except KeyError:
        raise ValueError(f"unknown method {method!r}; choose from {', '.join(METHODS)}") from None
    if isinstance(policy, CULVP):
        policy.partition = partition
        policy.news_whole = news == "whole"
        if news == "off":
            policy.news_rounds = policy.reconsider_every = 0
            policy.help_share = 0.0
    return policy  # type: ignore[no-any-return]


def make_team(
    method: str,
    shape: tuple[int, int],
    starts: list[tuple[int, int]],
    seed: int | np.random.SeedSequence,
    partition: str = "balanced",
    news: str = "on",
) -> list[ExplorerAgent]:
    """One agent per start cell, each with its own policy (``make_policy``) and an independent
    seeded stream."""
    seqs = (
        np.random.SeedSequence(seed).spawn(len(starts))
        if isinstance(seed, int)
        else seed.spawn(len(starts))
    )
    return [
        ExplorerAgent(
            i, shape, starts, make_policy(method, partition, news), np.random.default_rng(s)
        )
        for i, s in enumerate(seqs)
    ]


__all__ = [
    "AGENT",
    "CULVP",
    "EXCHANGES",
    "FREE",
    "METHODS",
    "NEWS",
    "OBSTACLE",
    "PARTITIONS",
    "STAY",
    "UNKNOWN",
    "CostUtilityBSO",
    "CostUtilityJGR",
    "CostUtilityMNM",
    "Drive",
    "Exchange",
    "ExplorerAgent",
    "Hedac",
    "Move",
    "NearestFrontier",
    "Peer",
    "Policy",
    "Request",
    "Rounds",
    "Sense",
    "View",
    "attracting_field",
    "explore_rounds",
    "make_policy",
    "make_team",
    "unexplored_in_view",
    "voronoi_partition",
]
