"""The node: one zenoh session per process, wrapped for asyncio.

A node joins a team, exports procedures, calls other members' procedures, broadcasts and
subscribes (range-limited or team-wide), and keeps a live view of the team. Use it as an async
context manager::

    async with Node("ernst", team=Team.from_env()) as node:
        node.export(add)
        total = await node.call("hugo", "add", 1, 2, timeout=1.0)
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import time
from collections import Counter
from collections.abc import Callable
from typing import Any, Literal

import zenoh

from . import _keys
from ._bridge import Portal, run_blocking, sample_size
from ._config import NodeConfig, Team
from ._exceptions import MoverError, NameTaken, PayloadTooLarge, WireError
from ._membership import Membership
from ._radio import Locator, Message, Neighbour, Radio, RadioModel, Subscription
from ._rpc import RpcClient, RpcServer, procedures_of
from ._wire import DEFAULT_MAX_SIZE, Opener, Sealer, Sessions, SessionUnknown, pack

log = logging.getLogger("mover.node")


def _array_header(n: int) -> bytes:
    """The msgpack header of an array of ``n`` elements."""
    if n < 16:
        return bytes([0x90 | n])
    if n < 65536:
        return b"\xdc" + n.to_bytes(2, "big")
    return b"\xdd" + n.to_bytes(4, "big")


class _RateLimitedLog:
    """Logs refusals, at most ``burst`` per source per minute (a flood must not flood logs)."""

    def __init__(self, owner: str, burst: int = 20) -> None:
        self.owner = owner
        self.burst = burst
        self._counts: Counter[str] = Counter()
        self._window = 0.0

    def warn(self, source: str, message: str) -> None:
        now = time.monotonic()
        if now - self._window > 60.0:
            self._counts.clear()
            self._window = now
        self._counts[source] += 1
        if self._counts[source] <= self.burst:
            log.warning("%s: %s", self.owner, message)


class Node:
    """One process's membership of a team: RPC, broadcasts, liveliness.

    ``on_refused`` says what a caller that fails authentication is told: ``"reply"`` sends it an
    unsigned refusal (it gets ``Refused``), ``"ignore"`` tells it nothing (it sees the robot as
    unknown). Either way nothing runs and a log line is written. An ``observer`` node (for
    tools like ``mover ps``) holds no liveliness token and is not a member.
    """

    def __init__(
        self,
        name: str,
        team: Team,
        *,
        kind: str = "robot",
        config: NodeConfig | None = None,
        locator: Locator | None = None,
        radio: RadioModel | None = None,
        max_size: int = DEFAULT_MAX_SIZE,
        on_refused: Literal["reply", "ignore"] = "reply",
        observer: bool = False,
        unique: bool = False,
    ) -> None:
        self.name = _keys.check_name("robot", name)
        self.team_config = team
        self.kind = kind
        self.config = config or NodeConfig()
        self.on_refused = on_refused
        self.observer = observer
        self.unique = unique
        self.started = time.time()
        self.stats: Counter[str] = Counter()
        self.radio = Radio(locator, radio)
        self._sealer = Sealer(team.name, name, team.key, max_size=max_size)
        self._opener = Opener(team.name, team.key, max_size=max_size)
        self._sessions = Sessions()
        self._refusal_log = _RateLimitedLog(name)
        self._server = RpcServer(self)
        self._server.export(self.procedures, "mover.procedures")
        self._client = RpcClient(self)
        self._subs: dict[str, tuple[Any, list[Subscription]]] = {}
        self._publishers: dict[tuple[str, bool, bool], Any] = {}
        self._outbox: dict[tuple[str, bool, bool], list[bytes]] = {}
        self._flush_scheduled = False
        self._declared: list[Any] = []
        self._session: Any = None
        self._portal: Portal = None  # type: ignore[assignment]  # set by open()
        self.team: Membership = Membership(self)

    @property
    def team_name(self) -> str:
        """The name of the team this node belongs to."""
        return self.team_config.name

    # -- lifecycle ------------------------------------------------------------------------------

    async def open(self) -> Node:
        """Open the zenoh session and join the team."""
        if self._session is not None:
            raise MoverError("node is already open")
        loop = asyncio.get_running_loop()
        self._portal = Portal(loop)
        conf = self.config.to_zenoh()
        self._session = await run_blocking(lambda: zenoh.open(conf))
        team, portal, session = self.team_config.name, self._portal, self._session
        self.team.on_leave(self._member_left)
        self.team.on_gone(self._server.cancel)  # a caller gone for good: stop its calls
        self._declared += [
            session.declare_queryable(
                _keys.rpc(team, self.name),
                portal.callback(self._server.on_query, size=sample_size),
                complete=True,
            ),
            session.declare_subscriber(
                _keys.ctl(team, self.name), portal.callback(self._on_ctl, size=sample_size)
            ),
            session.declare_queryable(
                _keys.hello(team, self.name), portal.callback(self.team.on_hello_query)
            ),
        ]
        self._declared.append(
            session.liveliness().declare_subscriber(
                _keys.alive(team, "*"), portal.callback(self.team.on_token), history=True
            )
        )
        if self.unique:
            await self._refuse_a_taken_name()
        if not self.observer:
            self._declared.append(session.liveliness().declare_token(_keys.alive(team, self.name)))
        return self

    async def _refuse_a_taken_name(self) -> None:
        """Refuse to start (NameTaken) if a live node of the team already answers to our name."""
        if self.config.connect:  # first reach the team, for at most 2 s
            deadline = time.monotonic() + 2.0
            while not self.connected() and time.monotonic() < deadline:  # noqa: ASYNC110
                await asyncio.sleep(0.02)  # zenoh offers no event for this: poll
        # The liveliness history says who is there: a token of our name is a holder.
        deadline = time.monotonic() + 0.5
        while not self.team.has_token(self.name) and time.monotonic() < deadline:  # noqa: ASYNC110
            await asyncio.sleep(0.02)
        holders = await self.team.holders(self.name)
        for _ in range(5):  # its token is there: its hello may take a moment to be routed
            if holders or not self.team.has_token(self.name):
                break
            await asyncio.sleep(0.2)
            holders = await self.team.holders(self.name)
        if holders or self.team.has_token(self.name):
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
        if self._session is None:
            return
        self._flush()
        tasks = list(self._server.tasks.values())
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        self._client.close()
        for _, subs in list(self._subs.values()):
            for sub in list(subs):
                sub.close()
        session, self._session = self._session, None
        assert self._portal is not None
        self._portal.close()
        await run_blocking(lambda: self._close_session(session))

    def _close_session(self, session: Any) -> None:
        for entity in reversed(self._declared):
            try:
                entity.undeclare()
            except Exception as exc:
                log.debug("undeclare failed: %s", exc)
        self._declared.clear()
        self._publishers.clear()
        session.close()

    async def __aenter__(self) -> Node:
        return await self.open()

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    def connected(self) -> bool:
        """Whether this node has a link to any other zenoh node (peer or router) now."""
        if self._session is None:
            return False
        info = self._session.info
        return bool(list(info.routers_zid()) or list(info.peers_zid()))

    @property
    def zenoh_session(self) -> Any:
        """The underlying zenoh session (for tools and benchmarks)."""
        return self._session

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
        if range is not None and range < 0:
            raise ValueError("range must be >= 0")
        where = self.radio.position()
        item = pack([data, list(where) if where else None, range])
        if len(item) > self._sealer.max_size // 2:
            raise PayloadTooLarge(f"broadcast of {len(item)} bytes is over the limit")
        box = self._outbox.get((topic, reliable, express))
        if box is None:
            _keys.check_topic(topic)
            box = self._outbox[(topic, reliable, express)] = []
        box.append(item)
        if not self._flush_scheduled:
            self._flush_scheduled = True
            asyncio.get_running_loop().call_soon(self._flush)

    def _flush(self) -> None:
        self._flush_scheduled = False
        if self._session is None:
            return
        outbox, self._outbox = self._outbox, {}
        limit = self._sealer.max_size // 2
        for (topic, reliable, express), items in outbox.items():
            pub = self._publisher(topic, reliable, express)
            start = 0
            while start < len(items):
                end, size = start, 0
                while end < len(items) and (end == start or size + len(items[end]) < limit):
                    size += len(items[end])
                    end += 1
                payload = (
                    b"\x92" + pack(topic) + _array_header(end - start) + b"".join(items[start:end])
                )
                pub.put(self._sealer.seal_packed("bc", payload))
                self.stats["sent.bc_frames"] += 1
                start = end
            self.stats["sent.bc"] += len(items)

    def _publisher(self, topic: str, reliable: bool, express: bool) -> Any:
        pub = self._publishers.get((topic, reliable, express))
        if pub is None:
            congestion = zenoh.CongestionControl.BLOCK if reliable else zenoh.CongestionControl.DROP
            pub = self._session.declare_publisher(
                _keys.broadcast(self.team_name, topic),
                congestion_control=congestion,
                express=express,
            )
            self._publishers[(topic, reliable, express)] = pub
        return pub

    def subscribe(self, topic: str, *, maxlen: int = 100_000) -> Subscription:
        """Messages on ``topic`` that reach this node, as an async iterator."""
        self._require_open()
        _keys.check_topic(topic)
        sub = Subscription(topic, maxlen, self._unsubscribe)
        entry = self._subs.get(topic)
        if entry is None:
            assert self._portal is not None
            zsub = self._session.declare_subscriber(
                _keys.broadcast(self.team_config.name, topic),
                self._portal.callback(self._on_bc, droppable=True, size=sample_size),
            )
            entry = (zsub, [])
            self._subs[topic] = entry
        entry[1].append(sub)
        return sub

    def _unsubscribe(self, sub: Subscription) -> None:
        entry = self._subs.get(sub.topic)
        if entry is None or sub not in entry[1]:
            return
        entry[1].remove(sub)
        if not entry[1]:
            del self._subs[sub.topic]
            if self._session is not None:
                entry[0].undeclare()

    def _on_bc(self, sample: Any) -> None:
        try:
            env = self._opener.open(sample.payload.to_bytes())
            if env.sender == self.name:
                return
            payload = env.payload
            if env.kind != "bc" or not isinstance(payload, list) or len(payload) != 2:
                raise WireError("not a broadcast envelope")
            topic, items = payload
            if not isinstance(topic, str) or not isinstance(items, list):
                raise WireError("not a broadcast envelope")
            self._sessions.admit(env, self.name, self._sealer.epoch)
        except SessionUnknown as exc:
            # a member this node has not verified yet (it just joined, or we did): ask for its
            # hello; what it sent before that does not count
            self.stats["refused.unverified"] += 1
            self.team.verify_soon(exc.envelope.sender)
            return
        except WireError as exc:
            self.stats["refused"] += 1
            self._refusal_log.warn("bc", f"dropped a broadcast on {sample.key_expr}: {exc}")
            return
        entry = self._subs.get(topic)
        if entry is None:
            return
        messages = self.radio.receive_all(env.sender, topic, items, env.timestamp)
        if messages:
            for sub in entry[1]:
                sub._put(messages)
        delivered = len(messages)
        self.stats["recv.bc"] += delivered

    def neighbours(self, max_age: float = 1.0) -> dict[str, Neighbour]:
        """Members heard by broadcast within the last ``max_age`` seconds, with range/bearing."""
        return self.radio.neighbours(max_age)

    # -- internals ------------------------------------------------------------------------------

    def _require_open(self) -> None:
        if self._session is None:
            raise MoverError("the node is not open (use 'async with Node(...)')")

    def _on_ctl(self, sample: Any) -> None:
        try:
            env = self._opener.open(sample.payload.to_bytes())
            self._sessions.admit(env, self.name, self._sealer.epoch)
        except WireError as exc:
            self.stats["refused"] += 1
            self._refusal_log.warn("ctl", f"dropped a control message: {exc}")
            return
        if env.kind == "cancel" and type(env.payload) is int:
            self._server.cancel(env.sender, env.payload)

    def _member_left(self, name: str) -> None:
        self._client.robot_left(name)
        self.radio.forget(name)


__all__ = ["Message", "Node"]
