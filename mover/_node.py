"""The node: one zenoh session per process, wrapped for asyncio.

A node joins a team, exports procedures, calls other members' procedures, broadcasts and
subscribes (range-limited or team-wide), and keeps a live view of the team. Use it as an async
context manager::

    async with Node("ernst", team=TeamCredentials.from_env()) as node:
        node.export(add)
        total = await node.call("hugo", "add", 1, 2, timeout=1.0)
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import time
from collections.abc import Callable
from typing import Any, Literal, Protocol

import zenoh

from . import _deprecated, _keys
from ._allocator import hold_thresholds
from ._bridge import Portal, run_blocking, sample_size
from ._config import NodeConfig, TeamCredentials
from ._exceptions import ConfigError, MoverError, NameTaken, Unreachable
from ._membership import Membership
from ._radio import Locator, Message, Neighbour, PubSub, Radio, RadioModel, Subscription
from ._rpc import RpcClient, RpcServer, procedures_of
from ._session import SessionState
from ._wire import DEFAULT_MAX_SIZE, Opener, Sealer

log = logging.getLogger("mover.node")

REACH_RETRY = (0.2, 5.0)
"""Seconds between tries to reach the router or peers at start: the first, and the most (it
doubles from one to the next)."""
REACH_SAY = 5.0
"""Seconds between the lines a node says while it cannot reach its router or peers."""


class _Declared(Protocol):
    """What the node declared on its session (queryables, subscribers, its token)."""

    def undeclare(self) -> object: ...


class Node:
    """One process's membership of a team: RPC, broadcasts, liveliness.

    ``on_refused`` says what a caller that fails authentication is told: ``"reply"`` sends it an
    unsigned refusal (it gets ``Refused``), ``"ignore"`` tells it nothing (it sees the robot as
    unknown). Either way nothing runs and a log line is written. An ``observer`` node (for
    tools like ``mover ps``) holds no liveliness token and is not a member.

    A node that cannot reach its router or peers when it opens (client mode: zenoh refuses to
    open) says so in one log line and tries again, backing off (:data:`REACH_RETRY`): a member
    until the network comes up, an observer (a tool, a CLI verb) for at most its
    ``config.patience``, then :class:`~mover.Unreachable`. A member that opened (a peer opens
    whether or not its peers answer) and has no link to anyone for :data:`REACH_SAY` seconds
    says so, every :data:`REACH_SAY` seconds, while zenoh keeps trying, and says when it has
    a link again.
    """

    def __init__(
        self,
        name: str,
        team: TeamCredentials,
        *,
        kind: str = "robot",
        config: NodeConfig | None = None,
        locator: Locator | None = None,
        radio: RadioModel | None = None,
        max_size: int = DEFAULT_MAX_SIZE,
        on_refused: Literal["reply", "ignore"] = "reply",
        observer: bool = False,
        unique: bool = False,
        reach_hint: str = "",
    ) -> None:
        self.name = _keys.check_name("robot", name)
        self.reach_hint = reach_hint  # what to check, said while the router does not answer
        self._watch: asyncio.Task[None] | None = None  # _watch_links, while open
        self.team_config = team
        self.kind = kind
        self.config = config or NodeConfig()
        self.on_refused = on_refused
        self.observer = observer
        self.unique = unique
        self.started = time.time()
        # What the parts below share, and all they see of this node.
        self._state = SessionState(
            name=self.name,
            team=team.name,
            sealer=Sealer(team.name, name, team.key, max_size=max_size),
            opener=Opener(team.name, team.key, max_size=max_size),
            kind=kind,
            config=self.config,
            observer=observer,
            on_refused=on_refused,
            started=self.started,
        )
        self.stats = self._state.stats
        self._sealer = self._state.sealer  # for tests that forge frames as this node
        self._sessions = self._state.peers
        self.radio = Radio(locator, radio)
        self.membership: Membership = Membership(self._state)  # who is in the team now
        self._server = RpcServer(self._state)
        self._server.export(self.procedures, "mover.procedures")
        self._client = RpcClient(self._state, self.membership)
        self._pubsub = PubSub(self._state, self.radio, self.membership)
        self._declared: list[_Declared] = []

    @property
    def team(self) -> Membership:
        """Deprecated name of :attr:`membership` (goes in the next release)."""
        _deprecated.warn("Node.team", "use Node.membership")
        return self.membership

    @property
    def team_name(self) -> str:
        """The name of the team this node belongs to."""
        return self.team_config.name

    # -- lifecycle ------------------------------------------------------------------------------

    async def open(self) -> Node:
        """Open the zenoh session and join the team."""
        if self._state.is_open:
            raise MoverError("node is already open")
        session = await self._reach()
        portal = Portal(asyncio.get_running_loop())
        self._state.opened(session, portal)
        team = self.team_config.name
        self.membership.on_leave(self._member_left)
        self.membership.on_gone(self._server.cancel)  # a caller gone for good: stop its calls
        self._declared += [
            session.declare_queryable(
                _keys.rpc(team, self.name),
                portal.callback(self._server.on_query, size=sample_size),
                complete=True,
            ),
            session.declare_subscriber(
                _keys.ctl(team, self.name), portal.callback(self._server.on_ctl, size=sample_size)
            ),
            session.declare_queryable(
                _keys.hello(team, self.name), portal.callback(self.membership.on_hello_query)
            ),
        ]
        self._declared.append(
            session.liveliness().declare_subscriber(
                _keys.alive(team, "*"), portal.callback(self.membership.on_token), history=True
            )
        )
        if self._endpoints() and not self.observer:
            self._watch = asyncio.get_running_loop().create_task(self._watch_links())
        if self.unique:
            await self._refuse_a_taken_name()
        if not self.observer:
            self._declared.append(session.liveliness().declare_token(_keys.alive(team, self.name)))
        return self

    async def _reach(self) -> zenoh.Session:
        """A zenoh session, once one of the endpoints answers (see the class docstring)."""
        hold_thresholds()  # before zenoh starts its threads
        loop = asyncio.get_running_loop()
        bound = self.config.patience if self.observer else None
        started = loop.time()
        wait, said, last = REACH_RETRY[0], "", 0.0
        while True:
            try:  # a new zenoh config each time: zenoh takes it
                session: zenoh.Session = await run_blocking(
                    lambda: zenoh.open(self.config.to_zenoh())
                )
            except zenoh.ZError as exc:
                why = str(exc).split("!")[0].split(" at /")[0].strip()
                if "Unable to connect" not in why:
                    raise ConfigError(f"cannot open a zenoh session: {why}") from None
                where = ", ".join(self._endpoints()) or "no endpoint"
                if bound is not None and loop.time() - started + wait > bound:
                    raise Unreachable(
                        f"cannot reach {where} within {bound:g} s (is the router up? "
                        "MOVER_CONNECT or the zenoh config names the endpoints)"
                    ) from None
                waited = loop.time() - started
                if not said or waited - last >= REACH_SAY:
                    said, last = where, waited
                    until = "until it answers" if bound is None else f"for {bound:g} s"
                    hint = f"; {self.reach_hint}" if self.reach_hint else ""
                    log.warning(
                        "%s: cannot reach %s (%.0f s): trying again %s%s",
                        self.name, where, waited, until, hint,
                    )  # fmt: skip
                await asyncio.sleep(wait)
                wait = min(wait * 2, REACH_RETRY[1])
                continue
            if said:
                log.warning("%s: reached %s after %.1f s", self.name, said, loop.time() - started)
            return session

    async def _watch_links(self) -> None:
        """While open: say when this node has had no link for REACH_SAY s (and every REACH_SAY
        s after), and when it has one again."""
        alone_since: float | None = None
        said = 0.0
        loop = asyncio.get_running_loop()
        while True:
            await asyncio.sleep(1.0)
            now = loop.time()
            if self.connected():
                if said:
                    log.warning(
                        "%s: linked again after %.0f s", self.name, now - (alone_since or now)
                    )
                alone_since, said = None, 0.0
                continue
            if alone_since is None:
                alone_since = now
            if now - alone_since >= REACH_SAY and now - said >= REACH_SAY:
                said = now
                hint = f"; {self.reach_hint}" if self.reach_hint else ""
                log.warning(
                    "%s: no link to %s (%.0f s): zenoh keeps trying%s",
                    self.name, ", ".join(self._endpoints()), now - alone_since, hint,
                )  # fmt: skip

    def _endpoints(self) -> list[str]:
        """The endpoints this node connects to (its settings, or its zenoh config file's)."""
        given = self.config.overrides.get("connect/endpoints", self.config.connect)
        if isinstance(given, dict):  # zenoh's per-mode form
            given = given.get(self.config.mode, [])
        return [str(e) for e in given] if isinstance(given, (list, tuple)) else []

    async def _refuse_a_taken_name(self) -> None:
        """Refuse to start (NameTaken) if a live node of the team already answers to our name."""
        if self.config.connect:  # first reach the team, for at most 2 s
            deadline = time.monotonic() + 2.0
            while not self.connected() and time.monotonic() < deadline:  # noqa: ASYNC110
                await asyncio.sleep(0.02)  # zenoh offers no event for this: poll
        # The liveliness history says who is there: a token of our name is a holder.
        deadline = time.monotonic() + 0.5
        while not self.membership.has_token(self.name) and time.monotonic() < deadline:  # noqa: ASYNC110
            await asyncio.sleep(0.02)
        holders = await self.membership.holders(self.name)
        for _ in range(5):  # its token is there: its hello may take a moment to be routed
            if holders or not self.membership.has_token(self.name):
                break
            await asyncio.sleep(0.2)
            holders = await self.membership.holders(self.name)
        if holders or self.membership.has_token(self.name):
            await self.close()
            who = (
                f"{holders[0].kind} pid {holders[0].pid} on {holders[0].host}"
                if holders
                else "a node that does not answer"
            )
            raise NameTaken(
                f"the name {self.name!r} is taken in team {self.team_name!r}: {who} holds it",
                holder=holders[0] if holders else None,
            )

    async def close(self) -> None:
        """Leave the team: cancel served calls, fail pending ones, close the session."""
        if not self._state.is_open:
            return
        if self._watch is not None:
            self._watch.cancel()
            self._watch = None
        self._pubsub.flush()
        await self._server.close()
        self._client.close()
        self._pubsub.close()
        session = self._state.closed()
        await run_blocking(lambda: self._close_session(session))

    def _close_session(self, session: zenoh.Session) -> None:
        for entity in reversed(self._declared):
            try:
                entity.undeclare()
            except Exception as exc:
                log.debug("undeclare failed: %s", exc)
        self._declared.clear()
        self._pubsub.closed()
        session.close()

    async def __aenter__(self) -> Node:
        return await self.open()

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    def connected(self) -> bool:
        """Whether this node has a link to any other zenoh node (peer or router) now."""
        return self._state.connected()

    @property
    def zenoh_session(self) -> zenoh.Session:
        """The underlying zenoh session (for tools and benchmarks; the node is open)."""
        return self._state.session()

    # -- procedures -----------------------------------------------------------------------------

    def export(self, fn: Callable[..., Any], name: str | None = None) -> Callable[..., Any]:
        """Let team members call ``fn`` (by ``name``, default its own). Usable as a decorator."""
        self._server.export(fn, name)
        return fn

    def procedures(self) -> dict[str, dict[str, str]]:
        """What this node exports (``mover.procedures``, for ``mover call ROBOT --list``): each
        procedure's signature and the first paragraph of its docstring."""
        out = {}
        for name, e in self._server.exports.items():
            first = (inspect.getdoc(e.fn) or "").strip().split("\n\n")[0]
            doc = " ".join(first.split())
            out[name] = {"signature": e.signature.describe(), "doc": doc[:160]}
        return out

    def export_all(self, obj: Any) -> list[str]:
        """Export every function marked with ``@procedure`` in a module, object or mapping."""
        found = procedures_of(obj)
        for name, fn in found.items():
            self._server.export(fn, name)
        return sorted(found)

    @property
    def exported(self) -> dict[str, str]:
        """Exported procedure names and their signatures."""
        return {n: e.signature.describe() for n, e in self._server.exports.items()}

    async def call(
        self, robot: str, procedure: str, *args: Any, timeout: float | None = 10.0, **kwargs: Any
    ) -> Any:
        """Run ``procedure(*args, **kwargs)`` on ``robot`` and return its result.

        Raises a :class:`~mover.CallError`: RemoteError (the procedure raised),
        UnknownProcedure, BadArguments, CallTimeout, RobotLost (the robot left mid-call),
        UnknownRobot, Refused. ``timeout=None`` waits as long as the robot stays a member.
        Cancelling the await cancels the procedure on the robot.
        """
        self._require_open()
        return await self._client.call(robot, procedure, args, kwargs, timeout)

    # -- broadcasts -----------------------------------------------------------------------------

    async def broadcast(
        self,
        topic: str,
        data: Any,
        *,
        range: float | None = None,
        reliable: bool = False,
        express: bool = False,
    ) -> None:
        """Send ``data`` on ``topic`` to members within ``range`` metres (see the nowait form)."""
        self.broadcast_nowait(topic, data, range=range, reliable=reliable, express=express)

    def broadcast_nowait(
        self,
        topic: str,
        data: Any,
        *,
        range: float | None = None,
        reliable: bool = False,
        express: bool = False,
    ) -> None:
        """Send ``data`` on ``topic`` to the members within ``range`` metres of this node now.

        ``range=None`` reaches the whole team. ``reliable=True`` blocks rather than drops when
        the network is congested (default: drop, as a radio would). ``express=True`` sends the
        frame at once rather than letting zenoh batch it with others for up to a millisecond or
        so (for messages on a latency-bound path, such as a lock-step tick). Broadcasts made in one
        turn of the event loop leave together, at the end of that turn, as one sealed frame per
        topic (so a burst costs one signature and one zenoh message); each keeps the position
        this node had when it was made. Raises PayloadTooLarge at once for oversized data.
        """
        self._require_open()
        self._pubsub.broadcast(topic, data, range, reliable, express)

    def subscribe(self, topic: str, *, maxlen: int = 100_000) -> Subscription:
        """Messages on ``topic`` that reach this node, as an async iterator."""
        self._require_open()
        return self._pubsub.subscribe(topic, maxlen)

    def neighbours(self, max_age: float = 1.0) -> dict[str, Neighbour]:
        """Members heard by broadcast within the last ``max_age`` seconds, with range/bearing."""
        return self.radio.neighbours(max_age)

    # -- internals ------------------------------------------------------------------------------

    def _require_open(self) -> None:
        self._state.require_open()

    def _member_left(self, name: str) -> None:
        self._client.robot_left(name)
        self.radio.forget(name)


__all__ = ["Message", "Node"]
