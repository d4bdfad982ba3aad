"""One exploring agent: its own map, what it hears, its region, its move (section III-A/B).

The agent is a plain object with no I/O, so the same class runs in an in-process experiment
and inside a robot process on a grid world. Per round the owner calls

1. ``observe(seen_cells=..., position=...)`` with what the star sensor saw;
2. ``outgoing_message()`` and broadcasts it (msgpack-able) to the agents within range;
3. ``observe(heard_messages=[...])`` with the messages heard this round (possibly none);
4. if it heard anyone, ``EXCHANGES - 1`` more times: ``relay_message()`` to the same agents,
   then ``hear_relay([...])`` with theirs (what an agent learns travels that many hops a round);
5. ``decide()`` and drives the returned move ``(d_row, d_col)``.

No central map: an agent decides only from its own map and what it has heard. Messages carry
only what changed since the agent's last message, except that when an agent hears a peer it did
not hear the round before, its next message carries its whole map (the newcomer missed the
deltas); a peer that stays in range has thus received everything the sender knows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ._grid import FREE, OBSTACLE, UNKNOWN, passable_mask, path_to, wavefront
from ._voronoi import balanced_partition, voronoi_partition

Move = tuple[int, int]
STAY: Move = (0, 0)
#: Map exchanges per round: the first carries position, goal and regions; the others relay
#: what was heard, so that news crosses a chain of agents in range of each other in one round
#: (the authors' code, which shares maps after every agent's move, reaches the whole chain).
#: 1 is the paper's one exchange per round.
EXCHANGES = 3


class Policy(Protocol):
    """A decision method (CU-LVP or a baseline): the agent's state -> its move."""

    name: str

    def decide(self, agent: ExplorerAgent) -> Move:
        """Choose this round's move for ``agent``."""
        ...


@dataclass(frozen=True)
class Peer:
    """What an agent heard from another this round: flat cell, goal, regions."""

    pos: int
    goal: int | None
    regions: frozenset[int]


class ExplorerAgent:
    """An agent's knowledge (map, region, peers heard) and its decision, seeded.

    ``starts`` are the whole team's start cells, known to every member at launch (as team
    membership is); each agent derives the same Voronoi partition from them.
    """

    def __init__(
        self,
        agent_id: int,
        shape: tuple[int, int],
        starts: list[tuple[int, int]],
        policy: Policy,
        rng: np.random.Generator,
    ) -> None:
        self.id = agent_id
        self.shape = (int(shape[0]), int(shape[1]))
        self.width = self.shape[1]
        self.policy = policy
        self.rng = rng
        self.known = np.full(self.shape, UNKNOWN, dtype=np.int8)
        self.known[0, :] = self.known[-1, :] = OBSTACLE  # the border is walled (IV-A)
        self.known[:, 0] = self.known[:, -1] = OBSTACLE
        self._flat = self.known.ravel()  # a view: writes go to ``known``
        self._border = self.known == OBSTACLE
        self.pos = self._index(starts[agent_id])
        # CU-LVP chooses regions to help with by an estimate of the work left in them (see
        # ``switch_region``); the baselines keep the plain rule.
        self._estimate = getattr(policy, "region_choice", "nearest") == "estimate"
        self._round = 0  # rounds heard so far (``observe(heard_messages=...)`` calls)
        self._last_heard = np.zeros(len(starts))  # round an agent holding region r was heard
        self._holders: dict[int, dict[int, int]] = {}  # region -> {agent: cell last heard at}
        # agent -> (round, cell, regions): the latest news of each agent, heard or passed on;
        # CU-LVP passes it on in its messages (``news_rounds``), the baselines do not
        self.gossip = getattr(policy, "news_rounds", 0) > 0
        self._whole_news: bool = getattr(policy, "news_whole", False)
        # each other agent lately known to hold a region takes this share of one's part of
        # it (``switch_region``; CU-LVP's ``help_share``)
        self._help_share: float = getattr(policy, "help_share", 0.0)
        self._news: dict[int, tuple[int, int, tuple[int, ...]]] = {}
        self._news_fresh: set[int] = set()  # agents whose news changed since our last message
        self._reconsidered = 0  # round a helper last chose its region again (``reconsider``)
        self._share: np.ndarray | None = None  # ``_share_of_region`` until the map, the
        # agent's cell, its regions or the agents heard change
        # Section III-B: regions from the initial map, where all unknown space counts as free.
        # CU-LVP balances their sizes (``partition = "balanced"``); the baselines keep the
        # plain Voronoi partition.
        split = (
            balanced_partition
            if getattr(policy, "partition", "voronoi") == "balanced"
            else voronoi_partition
        )
        self.region_of = split(self.known != OBSTACLE, list(starts)).ravel()
        self.regions: frozenset[int] = frozenset({agent_id})  # assigned: explored first
        self.merged: frozenset[int] = frozenset()  # regions of agents met, explored next
        self._in_region: np.ndarray = self.region_of == agent_id
        self._in_merged = np.zeros(self.region_of.shape, dtype=bool)
        self.goal: int | None = None
        self.peers: dict[int, Peer] = {}
        self._fresh = np.zeros(self._flat.size, dtype=bool)
        self._send_full = False
        self._heard_before: set[int] = set()
        self.stuck = 0
        self._dtype = "<u2" if self._flat.size <= 0xFFFF else "<u4"

    # -- coordinates -------------------------------------------------------------------------
    def _index(self, rc: tuple[int, int]) -> int:
        return int(rc[0]) * self.width + int(rc[1])

    def cell(self, k: int) -> tuple[int, int]:
        """``(row, col)`` of flat index ``k``."""
        return divmod(int(k), self.width)

    @property
    def position(self) -> tuple[int, int]:
        """The agent's cell."""
        return self.cell(self.pos)

    # -- sensing and hearing -----------------------------------------------------------------
    def observe(
        self,
        seen_cells: list[tuple[int, int, int]] | None = None,
        heard_messages: list[dict[str, Any]] | None = None,
        position: tuple[int, int] | None = None,
    ) -> None:
        """Record sensed cells ``(row, col, value)``, the agent's cell, and heard messages.

        Pass ``heard_messages`` (an empty list if nobody was heard) once per round: it replaces
        the peers heard last round.
        """
        self._share = None
        if position is not None:
            new = self._index(position)
            self.stuck = 0 if new != self.pos else self.stuck
            self.pos = new
        for r, c, v in seen_cells or ():
            k = r * self.width + c
            if self._flat[k] == UNKNOWN:
                self._flat[k] = v
                self._fresh[k] = True
        if heard_messages is not None:
            self._hear(heard_messages)

    def _hear(self, messages: list[dict[str, Any]]) -> None:
        peers: dict[int, Peer] = {}
        merged = set(self.merged)
        self._round += 1
        for msg in messages:
            sender = int(msg["id"])
            if sender == self.id:
                continue
            self._merge_cells(msg)
            goal = msg.get("goal")
            peer_regions = frozenset(int(r) for r in msg["regions"])
            peer = Peer(
                self._index(msg["pos"]), None if goal is None else self._index(goal), peer_regions
            )
            peers[sender] = peer
            self._news[sender] = (self._round, peer.pos, tuple(sorted(peer_regions)))
            self._news_fresh.add(sender)
            for r in peer_regions:
                self._last_heard[r] = self._round
            for r, holders in self._holders.items():
                if r not in peer_regions:
                    holders.pop(sender, None)
            for r in peer_regions:
                self._holders.setdefault(r, {})[sender] = peer.pos
            merged |= peer_regions  # section III-B: regions merge when agents are in range
        for msg in messages:
            self._merge_news(msg)
        if set(peers) - self._heard_before:
            self._send_full = True  # a newcomer missed our earlier deltas
        self._heard_before = set(peers)
        self.peers = peers
        merged -= self.regions
        if merged != self.merged:
            self.merged = frozenset(merged)
            self._in_merged = np.isin(self.region_of, list(self.merged))

    def _merge_cells(self, msg: dict[str, Any]) -> None:
        for key, value in (("free", FREE), ("obstacle", OBSTACLE)):
            idx = np.frombuffer(msg[key], dtype=self._dtype).astype(np.intp)
            new = idx[self._flat[idx] == UNKNOWN]
            self._flat[new] = value
            self._fresh[new] = True  # passed on in this agent's next message

    def _merge_news(self, msg: dict[str, Any]) -> None:
        """Take the news of agents a message passes on (``"news"``: id, round heard, cell,
        regions) where it is newer than this agent's; the regions' last-heard rounds and
        holders follow, as if the agent had heard those agents itself at that round."""
        for aid, rnd, pos, regions in msg.get("news", ()):
            if aid == self.id or self._news.get(aid, (-1,))[0] >= rnd:
                continue
            self._news[aid] = (rnd, pos, tuple(regions))
            self._news_fresh.add(aid)
            for r in regions:
                self._last_heard[r] = max(self._last_heard[r], rnd)
            for r, holders in self._holders.items():
                if r not in regions:
                    holders.pop(aid, None)
            for r in regions:
                self._holders.setdefault(r, {})[aid] = pos

    def _gossip(self, everything: bool) -> list[list[Any]]:
        """The news this agent passes on (``gossip``, CU-LVP's): each other agent's latest that
        changed since its last message, or with ``everything`` (a newcomer was heard, or
        ``news_whole``) all of it. A hearer keeps only news newer than its own, so the agents
        that heard the last message lose nothing by the difference."""
        fresh, self._news_fresh = self._news_fresh, set()
        if not self.gossip:
            return []
        everything = everything or self._whole_news
        return [
            [aid, rnd, pos, list(regions)]
            for aid, (rnd, pos, regions) in self._news.items()
            if everything or aid in fresh
        ]

    def _cells(self) -> dict[str, Any]:
        """The map cells learned since the last message (all of them for a newcomer)."""
        everything = self._send_full
        mask = (self._flat != UNKNOWN) & ~self._border.ravel() if everything else self._fresh
        self._send_full = False
        free = np.flatnonzero(mask & (self._flat == FREE)).astype(self._dtype)
        obstacle = np.flatnonzero(mask & (self._flat == OBSTACLE)).astype(self._dtype)
        self._fresh[:] = False
        out = {"id": self.id, "free": free.tobytes(), "obstacle": obstacle.tobytes()}
        news = self._gossip(everything)
        if news:
            out["news"] = news
        return out

    def outgoing_message(self) -> dict[str, Any]:
        """This round's broadcast: position, goal, regions and the map cells that changed."""
        return {
            **self._cells(),
            "pos": list(self.position),
            "goal": None if self.goal is None else list(self.cell(self.goal)),
            "regions": sorted(self.regions),
        }

    def relay_message(self) -> dict[str, Any]:
        """A further exchange of the round: the map cells heard since the last message (the
        whole map if a newcomer was heard), for the same agents; see :data:`EXCHANGES`."""
        return self._cells()

    def hear_relay(self, messages: list[dict[str, Any]]) -> None:
        """Merge the map cells of the relay messages heard (position and goals stay as heard
        in the round's first exchange)."""
        self._share = None
        for msg in messages:
            if int(msg["id"]) != self.id:
                self._merge_cells(msg)
                self._merge_news(msg)

    # -- regions -----------------------------------------------------------------------------
    def set_regions(self, regions: set[int] | frozenset[int]) -> None:
        """Assign ``regions`` (Voronoi region ids) to this agent; forget merged ones."""
        self.regions = frozenset(regions)
        self._share = None
        self._in_region = np.isin(self.region_of, list(self.regions))
        self.merged = frozenset()
        self._in_merged[:] = False

    def candidates(self) -> np.ndarray:
        """Flat mask of the cells where goals may lie: the unknown cells of the assigned
        region, or, once it is explored, of the regions merged from agents met (section III-B:
        "the primary focus remains on achieving complete coverage within the assigned
        region"). With ``region_choice = "estimate"`` (CU-LVP) only the assigned region: once
        it is explored, ``switch_region`` picks the next by the work estimated left in it; and
        of a region shared with other agents, the part nearer to itself than to them
        (``_share_of_region``), as long as that part has unknown cells."""
        unknown: np.ndarray = self._flat == UNKNOWN
        own: np.ndarray = unknown & self._in_region
        if self._estimate:
            share = own & self._share_of_region()
            return share if share.any() else own
        if own.any():
            return own
        merged: np.ndarray = unknown & self._in_merged
        return merged

    def _share_of_region(self) -> np.ndarray:
        """The cells this agent is nearer to (on its map) than every other agent it last heard
        holding the same region, at the cell it was heard at. Agents that share a region (its
        holder and the helpers that came to it) thus split it, each starting on its own side,
        rather than all chasing the unknown cells nearest to them, which the others have
        often explored already."""
        if self._share is not None:
            return self._share
        share = np.ones(self._flat.shape, dtype=bool)
        holders = {
            pid: cell
            for r in self.regions
            for pid, cell in self._holders.get(r, {}).items()
            if pid != self.id
        }
        if holders:
            passable = passable_mask(self.known)
            mine = np.array(wavefront(passable, self.pos, self.width)[0])
            mine[mine < 0] = self._flat.size
            for cell in holders.values():
                theirs = np.array(wavefront(passable, cell, self.width)[0])
                theirs[theirs < 0] = self._flat.size
                share &= mine <= theirs
        self._share = share
        return share

    def in_region(self) -> np.ndarray:
        """Flat mask of the agent's assigned region."""
        return self._in_region

    def switch_region(self, exclude_current: bool = False) -> bool:
        """Section III-B: once its region is explored, take the nearest region that still has
        unknown cells, judged from the agent's own map. Returns whether one was found.

        With ``region_choice = "estimate"`` (CU-LVP) the agent instead takes the region with
        the most work it estimates left when it would arrive: the region's unknown cells on its
        own map, less ``STALE_RATE`` cells for every round since it last heard an agent holding
        that region (that agent has been exploring it since; never heard: since the start) but
        at most ``STALE_CAP`` of them (a lone holder of a large region nobody has heard from
        has not done it all), divided by 1 + the policy's ``help_share`` for every other agent
        lately known to hold the region (heard, or passed on), less ``DIST_RATE`` cells per round of
        travel. Helpers thus go where nobody was heard working lately rather than to the
        nearest region, which a neighbour has often explored already; ties go to the nearer
        region. A helper chooses again every few rounds (``reconsider``)."""
        targets = (self._flat == UNKNOWN) & (self.region_of >= 0)
        if exclude_current:
            targets &= ~(self._in_region | self._in_merged)
        if self._estimate:
            return self._switch_by_estimate(targets)
        _, _, found = wavefront(
            passable_mask(self.known),
            self.pos,
            self.width,
            bytearray(targets.tobytes()),
            nearest_only=True,
        )
        if not found:
            return False
        self.set_regions({int(self.region_of[min(found)])})
        self.goal = None
        return True

    STALE_RATE = 4.0  # cells an agent is assumed to explore per round in its region
    STALE_CAP = 0.4  # at most this share of a region's unknown cells is assumed done unseen
    DIST_RATE = 8.0  # extra cells of estimated work a round of travel costs
    HELP_ROUNDS = 30  # other agents holding a region count while their news is this fresh

    def _helpers(self, region: int) -> int:
        """The other agents whose latest news (at most ``HELP_ROUNDS`` old) holds ``region``."""
        return sum(
            1
            for rnd, _, regions in self._news.values()
            if region in regions and rnd >= self._round - self.HELP_ROUNDS
        )

    def reconsider(self, every: int) -> None:
        """A helper (an agent holding a region not its own) chooses its region again every
        ``every`` rounds, as the work estimated left changes with the news."""
        if self.regions != frozenset({self.id}) and self._round - self._reconsidered >= every:
            self._reconsidered = self._round
            self.switch_region()

    def _switch_by_estimate(self, targets: np.ndarray) -> bool:
        dist, _, found = wavefront(
            passable_mask(self.known), self.pos, self.width, bytearray(targets.tobytes())
        )
        if not found:
            return False
        cells = np.array(found)
        region = self.region_of[cells]
        away = np.array(dist)[cells]
        best: tuple[tuple[float, int], int] | None = None
        for r in np.unique(region):
            here = region == r
            d = int(away[here].min())
            unknown = int(here.sum())
            done_unseen = min(
                self.STALE_RATE * (self._round + d - self._last_heard[r]), self.STALE_CAP * unknown
            )
            helping = self._helpers(r)
            left = (unknown - done_unseen) / (1 + self._help_share * helping) - self.DIST_RATE * d
            if best is None or (left, -d) > best[0]:
                best = ((left, -d), int(r))
        assert best is not None
        self.set_regions({best[1]})
        self.goal = None
        return True

    def recent_cells(self, rounds: int) -> list[int]:
        """Cells of the agents not heard this round whose news (heard, or passed on by others)
        is at most ``rounds`` rounds old: where they were then."""
        return [
            pos
            for aid, (rnd, pos, _) in self._news.items()
            if aid not in self.peers and rnd >= self._round - rounds
        ]

    # -- moving ------------------------------------------------------------------------------
    def peer_cells(self) -> list[int]:
        """Cells of the agents heard this round (the map's "agent" cells)."""
        return [p.pos for p in self.peers.values()]

    def senior_peer_cells(self) -> list[int]:
        """Cells of the agents heard this round whose id is smaller (they have the way)."""
        return [p.pos for pid, p in self.peers.items() if pid < self.id]

    def step_towards(
        self, goal: int, passable: bytearray, gain: list[int] | None = None
    ) -> Move | None:
        """One move along a shortest path to ``goal`` over ``passable``; None if unreachable.
        With ``gain`` (per cell) the path is, of the shortest ones, one with the most gain.

        If an agent heard this round stands on the next cell, the agent waits (``STAY``) and
        counts the round as blocked.
        """
        target = bytearray(len(passable))
        target[goal] = 1
        _, parent, found = wavefront(
            passable, self.pos, self.width, target, nearest_only=True, gain=gain
        )
        if not found:
            return None
        path = path_to(parent, self.pos, goal)
        if path and path[0] not in self.peer_cells():
            return self.move_to(path[0])
        self.stuck += 1
        return STAY

    def sidestep(self) -> Move:
        """A random move to a known free neighbour that no heard agent occupies."""
        taken = set(self.peer_cells())
        options = [
            m
            for m in (self.pos - self.width, self.pos + self.width, self.pos - 1, self.pos + 1)
            if self._flat[m] == FREE and m not in taken
        ]
        if not options:
            return STAY
        return self.move_to(options[int(self.rng.integers(len(options)))])

    def move_to(self, k: int) -> Move:
        """The move onto the 4-neighbour cell ``k``."""
        d = k - self.pos
        return {-self.width: (-1, 0), self.width: (1, 0), -1: (0, -1), 1: (0, 1)}[d]

    def decide(self) -> Move:
        """This round's move, chosen by the agent's policy."""
        return self.policy.decide(self)
