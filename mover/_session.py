"""What one process's parts share: who it is, its zenoh session, the one door into its loop,
its seal and its view of the peers' sessions, its counters and its rate-limited fault log.

A :class:`~mover.Node` makes one :class:`SessionState` and hands it to each of its parts — the
RPC server and client (:mod:`mover._rpc`), pub/sub (:mod:`mover._radio`) and membership
(:mod:`mover._membership`) — in their constructors; none of them reaches into the node or into
another part. The zenoh session and the portal exist only while the node is open
(:meth:`SessionState.opened` to :meth:`SessionState.closed`).
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import zenoh
from zenoh import Reply, Session

from ._bridge import Portal
from ._config import NodeConfig
from ._exceptions import MoverError
from ._ratelog import RateLog
from ._wire import Opener, Sealer, Sessions

log = logging.getLogger("mover.node")


@dataclass(eq=False)
class SessionState:
    """One process's membership of a team, as its parts share it (see the module).

    ``peers`` holds the verified sessions of the other members and the replay windows;
    ``stats`` counts what was sent, received and refused (``sent.call``, ``refused``, ...).
    """

    name: str
    team: str
    sealer: Sealer
    opener: Opener
    kind: str = "robot"
    config: NodeConfig = field(default_factory=NodeConfig)
    observer: bool = False
    on_refused: Literal["reply", "ignore"] = "reply"
    started: float = field(default_factory=time.time)
    peers: Sessions = field(default_factory=Sessions)
    stats: Counter[str] = field(default_factory=Counter)
    faults: RateLog = field(init=False)
    zenoh: Session | None = None  # the zenoh session while open
    portal: Portal | None = None  # the door into the loop while open

    def __post_init__(self) -> None:
        self.faults = RateLog(self.name, log)

    @property
    def is_open(self) -> bool:
        """Whether the zenoh session is open."""
        return self.zenoh is not None

    def opened(self, session: Session, portal: Portal) -> None:
        """The node opened ``session``; items from zenoh's threads go through ``portal``."""
        self.zenoh, self.portal = session, portal

    def closed(self) -> Session:
        """The node is closing: the session it must close (no part uses it any more)."""
        session, self.zenoh = self.session(), None
        if self.portal is not None:
            self.portal.close()
        return session

    def require_open(self) -> None:
        """Raise MoverError unless the node is open."""
        if self.zenoh is None:
            raise MoverError("the node is not open (use 'async with Node(...)')")

    def session(self) -> Session:
        """The zenoh session (the node is open)."""
        if self.zenoh is None:
            raise MoverError("the node is not open (use 'async with Node(...)')")
        return self.zenoh

    def door(self) -> Portal:
        """The portal (the node is open)."""
        if self.portal is None:
            raise MoverError("the node is not open (use 'async with Node(...)')")
        return self.portal

    def ask_all(
        self,
        key: str,
        payload: bytes | bytearray,
        on_reply: Callable[[Reply], None],
        on_done: Callable[[None], None],
        *,
        timeout: float,
        express: bool = False,
    ) -> None:
        """A zenoh get to every queryable on ``key`` (so that a stranger's queryable, complete
        or not, cannot take the query away from the member), every reply handed to
        ``on_reply`` on the loop, then ``on_done(None)`` when the query is finished."""
        self.session().get(
            key,
            self.door().callback(on_reply, on_done),
            payload=payload,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
            timeout=timeout,
            express=express,
        )

    def connected(self) -> bool:
        """Whether this node has a link to any other zenoh node (peer or router) now."""
        if self.zenoh is None:
            return False
        info = self.zenoh.info
        return bool(list(info.routers_zid()) or list(info.peers_zid()))
