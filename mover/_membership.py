"""Team membership: who is alive, verified by a signed hello, with join and leave events.

Every node holds a liveliness token ``mover/<team>/alive/<name>``. A token alone proves nothing
(anyone on the network can declare one), so when a token appears the node asks its holder for a
hello sealed under the team key and carrying a fresh challenge; only then is it a member, and
the hello tells the asker the member's session (see ``_wire.Sessions``). A token
that goes away (the process exited, was SIGKILLed — seen within milliseconds — or hung past its
lease, the team's patience) makes the member leave.

*Dead* and *unreachable* differ. A member whose session closed (it exited, or was killed: its
socket closed) leaves at once. A member whose link went silent (a partition, a stalled router, a
burst of loss) stays a member for the team's patience (``NodeConfig.patience``, the zenoh lease):
a node that waits for it may :meth:`Membership.probe` it, and one that does not answer is
*suspected* (:meth:`Membership.suspected`, one log line) until it answers again or leaves.

What a stranger's token costs is bounded: one question when it appears, and at most
``hello_retries`` more, backing off from 0.2 s to 3 s; at most :data:`MAX_RETRYING` names are
being asked again at once (the rest wait their turn, after the first question, which is never
held back: a member that joins during a flood answers it at once). A token that never proves
itself is counted in the rate-limited log (:mod:`mover._ratelog`): one line per interval for
all of them, whatever their number, as for junk answers to a hello.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import time
from collections.abc import AsyncIterator, Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import zenoh

from . import _keys
from ._exceptions import WireError
from ._ratelog import RateLog

if TYPE_CHECKING:
    from ._session import SessionState

log = logging.getLogger("mover.team")

MAX_RETRYING = 64
"""Names whose hello is asked again at once, at most (each unanswered token waits its turn)."""
PROBE_TIMEOUT = 2.0
"""Seconds a probed member has to answer a fresh hello before it is suspected: above the
slowest answer seen from a busy member across the impaired link (docs/network-lab.md)."""


@dataclass(frozen=True)
class MemberInfo:
    """What a member says of itself in its hello."""

    name: str
    kind: str
    started: float  # Unix time the member's node opened
    pid: int
    host: str

    @property
    def uptime(self) -> float:
        """Seconds since the member's node opened."""
        return max(0.0, time.time() - self.started)


@dataclass(frozen=True)
class MemberEvent:
    """A member joined or left."""

    kind: str  # "join" or "leave"
    name: str
    info: MemberInfo | None


class Membership:
    """The live view of a team's members, as seen by one node."""

    def __init__(self, state: SessionState) -> None:
        self._state = state
        self._members: dict[str, MemberInfo] = {}
        self._tokens: set[str] = set()
        self._listeners: list[asyncio.Queue[MemberEvent]] = []
        self._on_leave: list[Callable[[str], None]] = []
        self._changed = asyncio.Event()
        self._verifying: dict[str, list[asyncio.Future[bytes | None]]] = {}
        self._asked: dict[str, float] = {}  # name -> when a hello was last asked unprompted
        self._retrying: set[str] = set()  # tokens whose hello is being asked again
        self._waiting: dict[str, int] = {}  # tokens waiting their turn -> the attempt they are at
        self._suspected: dict[str, float] = {}  # member -> since when (monotonic) it is
        self.faults = RateLog(state.name, log)
        """The rate-limited log of what strangers did (fake tokens, junk hellos), with counts."""

    # -- the public view ------------------------------------------------------------------------

    def members(self) -> frozenset[str]:
        """The names of the verified members now alive (this node included)."""
        return frozenset(self._members)

    def info(self, name: str) -> MemberInfo | None:
        """What member ``name`` said of itself, or None if it is not a member."""
        return self._members.get(name)

    def __contains__(self, name: object) -> bool:
        return name in self._members

    async def events(self) -> AsyncIterator[MemberEvent]:
        """Join and leave events from now on (an async iterator)."""
        queue: asyncio.Queue[MemberEvent] = asyncio.Queue()
        self._listeners.append(queue)
        try:
            while True:
                yield await queue.get()
        finally:
            self._listeners.remove(queue)

    async def wait_for(self, names: Iterable[str], timeout: float = 10.0) -> None:
        """Wait until every one of ``names`` is a member; TimeoutError after ``timeout``."""
        wanted = set(names)
        async with asyncio.timeout(timeout):
            while not wanted <= self._members.keys():
                await self._wait_change()

    async def wait_gone(self, name: str, timeout: float = 10.0) -> None:
        """Wait until ``name`` is no longer a member; TimeoutError after ``timeout``."""
        async with asyncio.timeout(timeout):
            while name in self._members:
                await self._wait_change()

    async def wait_size(self, n: int, timeout: float = 10.0) -> None:
        """Wait until the team has at least ``n`` members; TimeoutError after ``timeout``."""
        async with asyncio.timeout(timeout):
            while len(self._members) < n:
                await self._wait_change()

    def suspected(self) -> dict[str, float]:
        """Members that did not answer their last :meth:`probe`: each one's seconds since it
        stopped answering. A suspected member is still a member: it leaves when its link has
        been silent for the patience, or at once if its session closes."""
        now = time.monotonic()
        return {name: now - since for name, since in self._suspected.items()}

    async def probe(self, names: Iterable[str], timeout: float = PROBE_TIMEOUT) -> dict[str, float]:
        """Ask each member of ``names`` (this node aside) for a fresh hello at once: one that
        does not answer within ``timeout`` is suspected (one log line, when it starts), one that
        answers is not (one line, if it was). The suspected among ``names``, as
        :meth:`suspected` gives them."""
        me = self._state.name
        asked = [n for n in dict.fromkeys(names) if n != me and n in self._members]
        answers = await asyncio.gather(*(self.verify(n, timeout, fresh=True) for n in asked))
        now = time.monotonic()
        patience = self._state.config.patience
        for name, epoch in zip(asked, answers, strict=True):
            if name not in self._members:
                continue  # it left meanwhile (_leave forgot it)
            if epoch is None and name not in self._suspected:
                self._suspected[name] = now - timeout
                log.warning(
                    "%s: %s suspected: no answer for %.0f s (lost if its link stays silent "
                    "for the patience, %g s)",
                    me, name, timeout, patience,
                )  # fmt: skip
            elif epoch is not None and self._suspected.pop(name, None) is not None:
                log.warning("%s: %s answers again", me, name)
        return {n: now - self._suspected[n] for n in asked if n in self._suspected}

    def has_token(self, name: str) -> bool:
        """Whether some node holds ``name``'s liveliness token now (verified or not)."""
        return name in self._tokens

    def on_leave(self, callback: Callable[[str], None]) -> None:
        """Call ``callback(name)`` on the loop whenever a member leaves."""
        self._on_leave.append(callback)

    def on_gone(self, callback: Callable[[str], None], grace: float | None = None) -> None:
        """Call ``callback(name)`` when a member left and has not come back within ``grace`` s
        (default: the node's ``NodeConfig.leave_grace``).

        For giving up what a member held (its calls, its body in a world): a link that flaps
        makes a member leave and join again within moments, and it should lose nothing.
        """
        loop = asyncio.get_running_loop()
        if grace is None:
            grace = self._state.config.leave_grace

        def later(name: str) -> None:
            if name not in self._members:
                callback(name)

        def left(name: str) -> None:
            loop.call_later(grace, later, name)

        self._on_leave.append(left)

    # -- driven by the node ---------------------------------------------------------------------

    async def _wait_change(self) -> None:
        self._changed.clear()
        await self._changed.wait()

    def _join(self, info: MemberInfo) -> None:
        fresh = info.name not in self._members
        self._members[info.name] = info
        if fresh:
            log.info("%s: %s joined (%s)", self._state.name, info.name, info.kind)
            self._emit(MemberEvent("join", info.name, info))

    def _leave(self, name: str) -> None:
        self._suspected.pop(name, None)
        info = self._members.pop(name, None)
        if info is None:
            return
        log.info("%s: %s left", self._state.name, name)
        self._emit(MemberEvent("leave", name, info))
        for callback in list(self._on_leave):
            try:
                callback(name)
            except Exception:
                log.exception("leave callback failed")

    def _emit(self, event: MemberEvent) -> None:
        self._changed.set()
        for queue in self._listeners:
            queue.put_nowait(event)

    def self_info(self) -> MemberInfo:
        """What this node's own liveliness token says of it (name, kind, start, pid, host)."""
        state = self._state
        return MemberInfo(state.name, state.kind, state.started, os.getpid(), os.uname().nodename)

    def on_token(self, sample: zenoh.Sample) -> None:
        """A liveliness token appeared or went away (runs on the loop)."""
        key = str(sample.key_expr)
        name = _keys.robot_of(key)
        if sample.kind == zenoh.SampleKind.DELETE:
            if name == self._state.name and self._state.is_open and not self._state.observer:
                return  # a stranger's token of our name went: ours stays while we are open
            self._tokens.discard(name)
            self._waiting.pop(name, None)
            self._leave(name)
            return
        self._tokens.add(name)
        if name == self._state.name:
            if not self._state.observer:
                self._join(self.self_info())
            return
        if name not in self._retrying and name not in self._waiting:  # else it is being asked
            self._ask_hello(name)

    def _ask_hello(self, name: str, attempt: int = 0) -> None:
        """Verify the holder of ``name``'s token; it joins once its hello answers."""
        if not self._state.is_open:
            self._retrying.clear()
            self._waiting.clear()
            return
        if name not in self._tokens or name in self._members:
            self._retried(name)
            return
        self._hello(name, attempt=attempt, join=True)

    def _retry(self, name: str, attempt: int) -> None:
        """Ask ``name`` again (``attempt``), later, or once its turn comes (see the module)."""
        if name not in self._retrying and len(self._retrying) >= MAX_RETRYING:
            self._waiting[name] = attempt
            return
        self._retrying.add(name)
        delay = min(0.2 * 2 ** (attempt - 1), 3.0)
        asyncio.get_running_loop().call_later(delay, self._ask_hello, name, attempt)

    def _retried(self, name: str) -> None:
        """``name`` is asked no more (it answered, left or gave up): the next one's turn."""
        self._retrying.discard(name)
        while self._waiting and len(self._retrying) < MAX_RETRYING:
            turn = next(iter(self._waiting))
            self._retry(turn, self._waiting.pop(turn))

    async def verify(self, name: str, timeout: float = 5.0, *, fresh: bool = False) -> bytes | None:
        """``name``'s session, verified with a fresh challenge (asked now unless known, or if
        ``fresh``); None if no member of that name answers within ``timeout``. Works for any
        node of the team, members and observers alike (no liveliness token needed)."""
        state = self._state
        if not fresh:
            epoch = state.peers.verified(name)
            if epoch is not None:
                return epoch
        future: asyncio.Future[bytes | None] = asyncio.get_running_loop().create_future()
        waiting = self._verifying.setdefault(name, [])
        waiting.append(future)
        if len(waiting) == 1 and state.is_open:
            self._hello(name, attempt=state.config.hello_retries, join=False)
        try:
            async with asyncio.timeout(timeout):
                return await asyncio.shield(future)
        except TimeoutError:
            return None
        finally:
            if future in waiting:
                waiting.remove(future)
            if not waiting:
                self._verifying.pop(name, None)

    def verify_soon(self, name: str) -> None:
        """Ask ``name`` for its hello now, unless that was asked within the last second."""
        now = time.monotonic()
        if now - self._asked.get(name, -1e9) < 1.0 or not self._state.is_open:
            return
        self._asked[name] = now
        while len(self._asked) > 4096:
            del self._asked[next(iter(self._asked))]
        self._hello(name, attempt=self._state.config.hello_retries, join=False)

    def _open_hello(self, frame: bytes, name: str, challenge: bytes) -> tuple[Any, MemberInfo]:
        """The envelope and member info of an authentic hello answering ``challenge``."""
        env = self._state.opener.open(frame)
        p = env.payload
        try:
            if env.kind != "hello" or env.sender != name or p.get("challenge") != challenge:
                raise WireError("hello does not answer our challenge")
            info = MemberInfo(
                name, str(p["kind"]), float(p["started"]), int(p["pid"]), str(p["host"])
            )
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise WireError(f"malformed hello: {exc}") from None
        return env, info

    async def holders(self, name: str, timeout: float = 1.0) -> list[MemberInfo]:
        """Other live nodes of the team that answer to ``name`` (this node excluded)."""
        state = self._state
        loop = asyncio.get_running_loop()
        challenge = os.urandom(16)
        found: list[MemberInfo] = []
        finished: asyncio.Future[None] = loop.create_future()

        def on_reply(reply: zenoh.Reply) -> None:
            if reply.ok is None:
                return
            try:
                env, info = self._open_hello(reply.ok.payload.to_bytes(), name, challenge)
            except WireError:
                return
            if env.epoch != state.sealer.epoch:
                found.append(info)

        def on_done(_: None) -> None:
            if not finished.done():
                finished.set_result(None)

        state.ask_all(_keys.hello(state.team, name), challenge, on_reply, on_done, timeout=timeout)
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(asyncio.shield(finished), timeout + 0.5)
        return found

    def _verified(self, name: str, epoch: bytes | None) -> None:
        for future in self._verifying.get(name, ()):
            if not future.done():
                future.set_result(epoch)

    def _hello(self, name: str, *, attempt: int, join: bool) -> None:
        state = self._state
        challenge = os.urandom(16)
        answered = False

        def on_reply(reply: zenoh.Reply) -> None:
            nonlocal answered
            if reply.ok is None or answered:
                return
            try:
                env, info = self._open_hello(reply.ok.payload.to_bytes(), name, challenge)
            except WireError as exc:
                self.faults.warn("hello", f"refused a hello from {name!r}: {exc}")
                return
            answered = True
            # Its session, as of this fresh answer: what it broadcast before does not count.
            state.peers.learn(name, env.epoch, env.counter)
            self._verified(name, env.epoch)
            if join:
                self._retried(name)
                if name in self._tokens:
                    self._join(info)

        def on_done(_: None) -> None:
            if answered:
                return
            if not join:
                self._verified(name, None)
                return
            if name in self._tokens and attempt < state.config.hello_retries:
                # No authentic answer (an overloaded machine, a link still coming up, or only
                # a stranger's answer on the member's key): ask again later.
                self._retry(name, attempt + 1)
                return
            self._retried(name)
            if name in self._tokens:
                self.faults.warn(
                    "tokens",
                    f"{name!r} holds a liveliness token but is not a verified member of team "
                    f"{state.team!r}",
                )

        state.ask_all(
            _keys.hello(state.team, name),
            challenge,
            on_reply,
            on_done,
            timeout=state.config.hello_timeout,
        )

    def on_hello_query(self, query: zenoh.Query) -> None:
        """Answer a hello request with a signed hello (runs on the loop)."""
        state = self._state
        with query:
            challenge = query.payload.to_bytes()[:32] if query.payload is not None else b""
            info = self.self_info()
            frame = state.sealer.seal(
                "hello",
                {
                    "challenge": challenge,
                    "kind": info.kind,
                    "started": info.started,
                    "pid": info.pid,
                    "host": info.host,
                },
            )
            query.reply(_keys.hello(state.team, state.name), frame)
