"""Remote procedure calls: what a node exports, how it serves calls, how it makes them.

A call is a zenoh ``get`` on ``mover/<team>/rpc/<robot>`` carrying a sealed ``call`` envelope
``[procedure, args, kwargs]``; the callee answers with one sealed ``reply`` envelope, either
``{"ok": result}`` or ``{"err": {"type", "message"}}``, then drops the query. Cancelling the
caller's await sends a sealed ``cancel`` to the callee, which cancels the procedure's task (its
``finally`` runs). A call to a member that leaves the team mid-call fails with RobotLost; a
caller that leaves has its calls cancelled on the callee.

A call reaches every queryable on the callee's key, an outsider's too, and an outsider can send
the frame on to the callee, sooner than the original if its path is faster. The callee admits
each call once (``Sessions``) and runs it once; it keeps the sealed answer of each call admitted
lately (:class:`_Answers`) and answers a copy of that call, whichever came first, with the same
sealed bytes, so an outsider that drops the answer to its copy leaves the caller's own query
answered all the same. The answer is sealed for the caller's session and opened once: handing it
to any query gives an outsider nothing it could not relay anyway (docs/security.md).
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Any, TypeVar

import zenoh

from . import _keys
from ._exceptions import (
    CALL_ERRORS,
    CallError,
    CallTimeout,
    NodeClosed,
    Refused,
    RemoteError,
    RobotLost,
    UnknownRobot,
    WireError,
)
from ._signature import Signature
from ._wire import Envelope, EnvelopeRefused, SessionChanged, read_refusal, refusal

if TYPE_CHECKING:
    from ._membership import Membership
    from ._session import SessionState

log = logging.getLogger("mover.rpc")
TOOL_PROBES = frozenset({"mover.status", "mover.programs"})  # answered unknown quietly

F = TypeVar("F", bound=Callable[..., Any])
_MARK = "__mover_procedure__"
# How long zenoh keeps a call open when the caller set no timeout; liveliness ends it sooner.
_NO_TIMEOUT = 7 * 24 * 3600.0
ANSWERS_KEPT = 10.0
"""Seconds at most a sealed answer is kept for a copy of its call (at least half of that)."""
ANSWERS_COUNT = 512
"""Answers kept at most per half of :data:`ANSWERS_KEPT` (twice that in all)."""
ANSWERS_BYTES = 4 * 1024 * 1024
"""Bytes of answers kept at most per half (one larger answer is kept alone)."""
WAITING = 8
"""Copies of one running call held at most until its answer (the rest: an unsigned refusal)."""
ASK_AGAIN = (0.2, 2.0)
"""Seconds a caller waits before it sends its call again, the same frame, after a query to a
member ended refused (unsigned) and with no answer it believes: the first time, and at most
(doubling between)."""
_GONE = object()


def procedure(fn: F | None = None, *, name: str | None = None) -> Any:
    """Mark a function as a procedure other team members may call (see ``Node.export_all``)."""

    def mark(f: F) -> F:
        setattr(f, _MARK, name or f.__name__)
        return f

    return mark(fn) if fn is not None else mark


def procedures_of(obj: Any) -> dict[str, Callable[..., Any]]:
    """The functions marked with :func:`procedure` in a module, class instance or mapping."""
    items = obj.items() if isinstance(obj, dict) else ((n, getattr(obj, n)) for n in dir(obj))
    found = {}
    for _, value in items:
        mark = getattr(value, _MARK, None)
        if isinstance(mark, str) and callable(value):
            found[mark] = value
    return found


@dataclass
class Exported:
    """One exported procedure."""

    name: str
    fn: Callable[..., Any]
    signature: Signature
    is_async: bool = field(init=False)

    def __post_init__(self) -> None:
        self.is_async = inspect.iscoroutinefunction(self.fn)


class RpcServer:
    """Serves the calls addressed to one node."""

    def __init__(self, state: SessionState) -> None:
        self.state = state
        self.exports: dict[str, Exported] = {}
        self.tasks: dict[tuple[str, int], asyncio.Task[None]] = {}
        self._asked: dict[tuple[str, int], bool] = {}  # calls their caller asked to cancel
        self.answers = _Answers()

    def export(self, fn: Callable[..., Any], name: str | None = None) -> None:
        name = name or getattr(fn, _MARK, None) or fn.__name__
        _keys.check_name("procedure", name)
        self.exports[name] = Exported(name, fn, Signature(fn))

    def on_query(self, query: zenoh.Query) -> None:
        """An incoming call (runs on the loop)."""
        state = self.state
        frame = query.payload.to_bytes() if query.payload is not None else b""
        try:
            env = state.opener.open(frame)
            if env.kind != "call":
                raise EnvelopeRefused(f"a {env.kind!r} envelope is not a call", env)
            state.peers.admit(env, state.name, state.sealer.epoch)
        except WireError as exc:
            if (
                type(exc) is EnvelopeRefused
                and exc.envelope.kind == "call"
                and self.answers.again(query, exc.envelope.nonce, self._reply)
            ):
                # A copy of a call admitted lately (an outsider's, or the original after an
                # outsider's copy): the same sealed answer, now or when the call ends.
                state.stats["answered.again"] += 1
                state.faults.warn("rpc", f"answered a copy of a call again: {exc}")
                return
            state.stats["refused"] += 1
            state.faults.warn("rpc", f"refused a call: {exc}")
            if isinstance(exc, SessionChanged) and exc.envelope.kind == "call":
                # A call for an earlier session of this node: a sealed answer its caller can
                # believe, and asks again on. The only refusal sealed: a replayed call is an
                # outsider relaying a member's call, and a sealed "replayed" it could hand back
                # would end the caller's call (README, Security: relaying).
                self._send(query, exc.envelope, _err("SessionChanged", str(exc)))
                return
            with query:
                if state.on_refused == "reply":
                    query.reply(_keys.rpc(state.team, state.name), refusal(str(exc)))
            return
        state.stats["recv.call"] += 1
        prepared = self._prepare(env)
        if isinstance(prepared, dict):
            self._send(query, env, prepared)
            return
        exported, args, kwargs = prepared
        if not exported.is_async:
            # A plain function runs here and now, on the loop: no task, no extra loop turn.
            result = self._outcome(exported, lambda: exported.fn(*args, **kwargs))
            if not inspect.isawaitable(result):
                self._send(query, env, result)
                return
            awaitable = result
        else:
            awaitable = exported.fn(*args, **kwargs)
        self.answers.running(env.nonce)  # a copy that comes meanwhile waits for the answer
        task = asyncio.get_running_loop().create_task(self._serve(query, env, exported, awaitable))
        self.tasks[(env.sender, env.call_id)] = task

        def done(_: asyncio.Task[None]) -> None:
            self.tasks.pop((env.sender, env.call_id), None)
            self._asked.pop((env.sender, env.call_id), None)
            if inspect.iscoroutine(awaitable):
                awaitable.close()  # a no-op unless cancelled before it ever ran

        task.add_done_callback(done)

    async def _serve(
        self, query: zenoh.Query, env: Envelope, exported: Exported, awaitable: Awaitable[Any]
    ) -> None:
        try:
            result = await awaitable
        except asyncio.CancelledError:
            # The caller asked for it: say so. Cancelled because this node is closing: say
            # nothing, the caller sees the callee leave (RobotLost), not an answered error.
            if self._asked.pop((env.sender, env.call_id), False):
                self._send(query, env, _err("Cancelled", "the call was cancelled"))
            raise
        except Exception as exc:
            self._send(query, env, self._failure(exported, exc))
            return
        self._send(query, env, {"ok": result})

    def _prepare(
        self, env: Envelope
    ) -> dict[str, Any] | tuple[Exported, list[Any], dict[str, Any]]:
        """The procedure and its checked arguments, or the error to reply with."""
        payload = env.payload
        if not (
            isinstance(payload, list)
            and len(payload) == 3
            and isinstance(payload[0], str)
            and isinstance(payload[1], list)
            and isinstance(payload[2], dict)
        ):
            return _err("BadArguments", "a call must carry [procedure, args, kwargs]")
        name, args, kwargs = payload
        exported = self.exports.get(name)
        if exported is None:
            # a tool asking a member that hosts no programs (`mover ps`) is not a fault here
            say = log.debug if name in TOOL_PROBES else log.warning
            say("%s: %r called unknown procedure %r", self.state.name, env.sender, name)
            known = ", ".join(sorted(self.exports)) or "none"
            return _err(
                "UnknownProcedure",
                f"{self.state.name!r} exports no procedure {name!r} (exported: {known})",
            )
        try:
            args, kwargs = exported.signature.bind(args, kwargs)
        except TypeError as exc:
            log.warning(
                "%s: bad arguments from %r to %r: %s", self.state.name, env.sender, name, exc
            )
            return _err("BadArguments", f"{name}{exported.signature.describe()}: {exc}")
        return exported, args, kwargs

    def _outcome(self, exported: Exported, run: Callable[[], Any]) -> Any:
        """Run a plain procedure: the reply body, or an awaitable it returned."""
        try:
            result = run()
        except Exception as exc:
            return self._failure(exported, exc)
        return result if inspect.isawaitable(result) else {"ok": result}

    def _failure(self, exported: Exported, exc: Exception) -> dict[str, Any]:
        log.info(
            "%s: procedure %r raised %s: %s",
            self.state.name,
            exported.name,
            type(exc).__name__,
            exc,
        )
        return _err(type(exc).__name__, str(exc))

    def _send(self, query: zenoh.Query, env: Envelope, reply: dict[str, Any]) -> None:
        state = self.state
        try:
            frame = state.sealer.seal(
                "reply", reply, env.call_id, to=env.sender, to_epoch=env.epoch
            )
        except WireError as exc:
            failed = _err("WireError", f"cannot send the result: {exc}")
            frame = state.sealer.seal(
                "reply", failed, env.call_id, to=env.sender, to_epoch=env.epoch
            )
        self._reply(query, frame)
        waiting = self.answers.keep(env.nonce, frame)
        if waiting is not None:  # copies of the call that came while it ran
            for other in waiting:
                self._reply(other, frame)

    def _reply(self, query: zenoh.Query, frame: bytes | bytearray) -> None:
        state = self.state
        with query:
            try:
                query.reply(_keys.rpc(state.team, state.name), frame, express=True)
                state.stats["sent.reply"] += 1
            except Exception as exc:  # the session is closing, or the caller is gone
                log.debug("could not reply to %s: %s", query.key_expr, exc)

    def cancel(self, caller: str, call_id: int | None = None) -> None:
        """Cancel one call of ``caller`` (or all of them)."""
        for (who, cid), task in list(self.tasks.items()):
            if who == caller and (call_id is None or cid == call_id):
                self._asked[(who, cid)] = True
                task.cancel()

    def on_ctl(self, sample: zenoh.Sample) -> None:
        """A control message (a caller's cancel) on ``mover/<team>/ctl/<me>`` (on the loop)."""
        state = self.state
        try:
            env = state.opener.open(sample.payload.to_bytes())
            state.peers.admit(env, state.name, state.sealer.epoch)
        except WireError as exc:
            state.stats["refused"] += 1
            state.faults.warn("ctl", f"dropped a control message: {exc}")
            return
        if env.kind == "cancel" and type(env.payload) is int:
            self.cancel(env.sender, env.payload)

    async def close(self) -> None:
        """Cancel every call being served, and wait for them to end."""
        tasks = list(self.tasks.values())
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        self.answers.clear()


class _Answers:
    """The sealed answers of the calls admitted lately, by the call's nonce, for copies of them.

    Two generations of dicts, the older dropped whole when the newer is turned (every
    ``ANSWERS_KEPT / 2`` seconds, by a timer armed while any answer is kept, or sooner at
    ``ANSWERS_COUNT`` answers or ``ANSWERS_BYTES``): an answer is kept from half that long to
    that long, and a call costs one dict entry (no timestamp, no object of its own). A call
    still running has ``None`` (no copy waiting) or the list of the copies' queries waiting.
    """

    def __init__(self) -> None:
        self._new: dict[bytes, Any] = {}
        self._old: dict[bytes, Any] = {}
        self._bytes = 0
        self._timer: asyncio.TimerHandle | None = None

    def __len__(self) -> int:
        return len(self._new) + len(self._old)

    def running(self, nonce: bytes) -> None:
        """The call ``nonce`` was admitted and runs (its answer comes later)."""
        self._room(0)
        self._new[nonce] = None

    def keep(self, nonce: bytes, frame: bytes | bytearray) -> list[zenoh.Query] | None:
        """Keep the sealed answer of call ``nonce``; the copies' queries that waited for it."""
        waiting = self._new.get(nonce)
        if waiting is None and self._old:
            waiting = self._old.pop(nonce, None)
        self._room(len(frame))
        self._new[nonce] = frame
        self._bytes += len(frame)
        return waiting

    def again(
        self,
        query: zenoh.Query,
        nonce: bytes,
        reply: Callable[[zenoh.Query, bytes | bytearray], None],
    ) -> bool:
        """Answer a copy of call ``nonce``: at once if answered, when it is if it runs; False
        if the call is not known (or too many copies wait)."""
        held = self._new.get(nonce, _GONE)
        where = self._new
        if held is _GONE:
            held, where = self._old.get(nonce, _GONE), self._old
        if held is _GONE:
            return False
        if held is None:
            where[nonce] = [query]
        elif isinstance(held, list):
            if len(held) >= WAITING:
                return False
            held.append(query)
        else:
            reply(query, held)
        return True

    def _room(self, size: int) -> None:
        if len(self._new) >= ANSWERS_COUNT or self._bytes + size > ANSWERS_BYTES:
            self._turn()
        if self._timer is None:
            self._timer = asyncio.get_running_loop().call_later(ANSWERS_KEPT / 2, self._tick)

    def _tick(self) -> None:
        self._timer = None
        self._turn()
        if self._new or self._old:
            self._timer = asyncio.get_running_loop().call_later(ANSWERS_KEPT / 2, self._tick)

    def _turn(self) -> None:
        self._old, self._new = self._new, {}
        self._bytes = 0

    def clear(self) -> None:
        """Forget every answer (the node closes)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._new.clear()
        self._old.clear()
        self._bytes = 0


def _err(kind: str, message: str) -> dict[str, Any]:
    return {"err": {"type": kind, "message": message}}


@dataclass
class _Pending:
    robot: str
    procedure: str
    future: asyncio.Future[Any]
    was_member: bool
    ask: Callable[[], None]  # sends the call's sealed frame (again)
    refusal: str | None = None
    refused: bool = False  # an unsigned refusal came to the query now open
    asked: int = 1  # how often the frame was sent


class RpcClient:
    """Makes calls from one node and tracks the ones in flight."""

    def __init__(self, state: SessionState, team: Membership) -> None:
        self.state = state
        self.team = team
        self.pending: dict[int, _Pending] = {}
        self._next_id = 0

    async def call(
        self,
        robot: str,
        procedure: str,
        args: tuple[Any, ...],
        kwargs: dict[str, Any],
        timeout: float | None,
    ) -> Any:
        _keys.check_name("robot", robot)
        loop = asyncio.get_running_loop()
        deadline = None if timeout is None else loop.time() + timeout
        for attempt in (1, 2):
            left = None if deadline is None else max(0.0, deadline - loop.time())
            epoch = await self._session_of(robot, procedure, left, fresh=attempt > 1)
            try:
                return await self._call(robot, epoch, procedure, args, kwargs, timeout, left)
            except _SessionChanged:  # the callee restarted since we learned its session
                continue
        raise Refused(f"{robot!r} keeps changing sessions", robot=robot, procedure=procedure)

    async def _session_of(
        self, robot: str, procedure: str, timeout: float | None, *, fresh: bool
    ) -> bytes:
        """The callee's session, verified with a challenge (asked now if not known yet)."""
        state = self.state
        if robot == state.name:
            return state.sealer.epoch
        epoch = None if fresh else state.peers.verified(robot)
        if epoch is None:
            epoch = await self.team.verify(robot, timeout=min(timeout or 5.0, 5.0), fresh=fresh)
        if epoch is None:
            raise UnknownRobot(
                f"no member {robot!r} of team {state.team!r} answers",
                robot=robot,
                procedure=procedure,
            )
        return epoch

    async def _call(
        self,
        robot: str,
        epoch: bytes,
        procedure: str,
        args: tuple[Any, ...],
        kwargs: dict[str, Any],
        timeout: float | None,
        left: float | None,
    ) -> Any:
        state = self.state
        self._next_id += 1
        call_id = self._next_id
        payload = [procedure, list(args), kwargs]
        frame = state.sealer.seal("call", payload, call_id, to=robot, to_epoch=epoch)
        loop = asyncio.get_running_loop()
        future: asyncio.Future[Any] = loop.create_future()
        end = None if left is None else loop.time() + left

        def ask() -> None:
            # Only the member's authentic reply counts (see _on_reply).
            state.ask_all(
                _keys.rpc(state.team, robot),
                frame,
                partial(self._on_reply, call_id),
                partial(self._on_done, call_id),
                timeout=_NO_TIMEOUT if end is None else max(0.0, end - loop.time()) + 1.0,
                express=True,
            )

        self.pending[call_id] = _Pending(robot, procedure, future, robot in self.team, ask)
        try:
            ask()
            state.stats["sent.call"] += 1
            try:
                async with asyncio.timeout(left):
                    return await future
            except TimeoutError:
                self._cancel_remote(robot, epoch, call_id)
                said = self.pending[call_id].refusal
                heard = f" (an unauthenticated refusal said: {said})" if said else ""
                raise CallTimeout(
                    f"{procedure!r} on {robot!r} did not answer within {timeout} s{heard}",
                    robot=robot,
                    procedure=procedure,
                ) from None
            except asyncio.CancelledError:
                if future.cancelled():  # awaiting it was cancelled, not answered
                    self._cancel_remote(robot, epoch, call_id)
                raise
        finally:
            self.pending.pop(call_id, None)

    def _cancel_remote(self, robot: str, epoch: bytes, call_id: int) -> None:
        state = self.state
        try:
            state.session().put(
                _keys.ctl(state.team, robot),
                state.sealer.seal("cancel", call_id, call_id, to=robot, to_epoch=epoch),
            )
            state.stats["sent.cancel"] += 1
        except Exception as exc:
            log.debug("could not send cancel to %r: %s", robot, exc)

    def _on_reply(self, call_id: int, reply: zenoh.Reply) -> None:
        p = self.pending.get(call_id)
        if p is None or p.future.done():
            return
        sample = reply.ok
        if sample is None:
            return  # zenoh's own errors (e.g. its timeout): our timers decide
        frame = sample.payload.to_bytes()
        state = self.state
        reason = read_refusal(frame)
        if reason is not None:
            # Unsigned: anyone could have sent it. It counts only if nothing authentic comes
            # before the query ends (_on_done): a caller whose key the callee refused hears why.
            p.refusal, p.refused = reason, True
            state.stats["recv.refusal"] += 1
            return
        try:
            env = state.opener.open(frame)
            if env.kind != "reply" or env.sender != p.robot or env.call_id != call_id:
                raise WireError("reply does not match the call")
            state.peers.admit(env, state.name, state.sealer.epoch)
            body = env.payload
            if not isinstance(body, dict):
                raise WireError("reply body is not a map")
        except WireError as exc:
            state.stats["refused.reply"] += 1
            state.faults.warn("reply", f"dropped a reply from {p.robot!r}: {exc}")
            return
        state.stats["recv.reply"] += 1
        if "ok" in body:
            p.future.set_result(body["ok"])
        elif isinstance(body.get("err"), dict) and body["err"].get("type") == "SessionChanged":
            p.future.set_exception(_SessionChanged())
        else:
            p.future.set_exception(self._error(p, body.get("err")))

    @staticmethod
    def _error(p: _Pending, err: Any) -> CallError:
        if not isinstance(err, dict):
            err = {"type": "WireError", "message": f"malformed error {err!r}"}
        kind, message = str(err.get("type")), str(err.get("message"))
        cls = CALL_ERRORS.get(kind)
        if cls is not None:
            return cls(message, robot=p.robot, procedure=p.procedure)
        return RemoteError(kind, message, robot=p.robot, procedure=p.procedure)

    def _on_done(self, call_id: int, _: None) -> None:
        p = self.pending.get(call_id)
        if p is None or p.future.done():
            return
        if p.was_member:
            # The query ended with no authentic answer (no route for now, or only a stranger
            # answered): the member's liveliness, or the caller's timeout, decides. If it was
            # refused, unsigned (copies of our frame that came first took every place the
            # callee holds for a running call), ask again, the same frame: the callee runs a
            # call once and answers each copy of it with the sealed answer it keeps.
            if p.refused:
                p.refused = False
                first, most = ASK_AGAIN
                wait = min(most, first * 2 ** (p.asked - 1))
                asyncio.get_running_loop().call_later(wait, self._ask_again, call_id)
            return
        if p.refusal is not None:
            exc: CallError = Refused(
                f"{p.robot!r} refused the call: {p.refusal}", robot=p.robot, procedure=p.procedure
            )
        elif p.was_member:
            exc = RobotLost(
                f"{p.robot!r} was lost during {p.procedure!r}", robot=p.robot, procedure=p.procedure
            )
        else:
            exc = UnknownRobot(
                f"no member {p.robot!r} of team {self.state.team!r} answers",
                robot=p.robot,
                procedure=p.procedure,
            )
        p.future.set_exception(exc)

    def _ask_again(self, call_id: int) -> None:
        p = self.pending.get(call_id)
        if p is None or p.future.done() or not self.state.is_open:
            return
        p.asked += 1
        p.ask()
        self.state.stats["sent.call_again"] += 1

    def robot_left(self, robot: str) -> None:
        for p in self.pending.values():
            if p.robot == robot and not p.future.done():
                p.future.set_exception(
                    RobotLost(
                        f"{robot!r} left the team during {p.procedure!r}",
                        robot=robot,
                        procedure=p.procedure,
                    )
                )

    def close(self) -> None:
        for p in self.pending.values():
            if not p.future.done():
                p.future.set_exception(NodeClosed("the node closed during the call"))


class _SessionChanged(Exception):
    """The callee answered that the call was for an earlier session of it: ask again."""
