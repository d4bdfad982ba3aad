"""Start a team's processes, watch them, and stop them all: the engine of ``mover up``.

Every process gets its own session (process group), so a terminal's Ctrl-C reaches only
``mover up``, which then stops the team in order: SIGINT to every member's group (their clean
exit), SIGTERM after ``STOP_GRACE`` seconds, SIGKILL after ``KILL_GRACE`` more; the router last.
No orphan is left if ``mover up`` itself is killed: each child is started through a few lines
of Python that ask Linux for SIGKILL when their parent dies (``PR_SET_PDEATHSIG``, kept across
``exec``) and exit if the parent is already gone; elsewhere this guard is skipped. SIGKILL, not
SIGTERM: with nobody left to wait for them, a clean exit that hangs would be an orphan (an
orderly stop is ``mover up``'s own, above). The guard runs in the child after ``exec``, not as a
``preexec_fn``, which would run Python in a fork of a process with zenoh's threads.

Each process's standard output and error go through one pipe to its log file in the run folder
(``<name>.log``) and, prefixed with ``[name]``, to this process's standard output. Readiness is
membership: ``mover up`` is a member itself (kind ``tool``, named ``up``) and waits until the
world and every member are members of the team, while any process that exits first fails the
wait at once with its last words.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import signal
import time
from collections.abc import Awaitable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Self, TypeVar

from .._config import NodeConfig, TeamCredentials, free_port
from .._exceptions import ConfigError, MoverError
from .._node import Node
from .._procs import Child, Processes, ProcessExited, start, stop
from .._programs import launch
from . import _hosts
from ._plan import ProcessPlan, Seeds, processes, resolved, seeds, uses_router
from ._teamfile import MAX_WAIT, SUPERVISOR, TeamPlan

_T = TypeVar("_T")

STOP_GRACE = 5.0
"""Seconds a process has to end after SIGINT before it gets SIGTERM."""
KILL_GRACE = 2.0
"""Seconds after SIGTERM before SIGKILL."""
ROUTER_READY = 10.0
"""Seconds a router has to say it listens."""


class UpError(Exception):
    """``mover up`` cannot go on: one line saying why. (A process that ended the team cannot
    do without, or one that ended before it was ready, is a :class:`ProcessExited`.)"""


class Stopped(Exception):
    """The team was asked to stop (Ctrl-C or SIGTERM)."""


@dataclass
class _Child:
    plan: ProcessPlan
    process: Child
    said_ready: asyncio.Event = field(default_factory=asyncio.Event)
    ready: bool = False  # seen serving: a member of the team, or its ready line said

    @property
    def proc(self) -> asyncio.subprocess.Process:
        return self.process.proc


class Supervisor(Processes):
    """One team, up: ``async with Supervisor(plan, out=run_dir) as up: await up.wait_ready()``.

    On entry the run folder is made (with ``team.json``, the file as run) and every process
    started; on exit every process is stopped. ``echo`` prints the processes' lines and this
    supervisor's own on standard output. ``signals`` turns SIGINT and SIGTERM into a stop
    (:meth:`guard` then raises :class:`Stopped`). The processes log at ``log_level``, else the
    file's ``log_level``, else ``$MOVER_LOG_LEVEL``, else WARNING.
    """

    def __init__(
        self,
        plan: TeamPlan,
        *,
        out: Path,
        seed: int | None = None,
        echo: bool = True,
        signals: bool = True,
        log_level: str | None = None,
        host: str | None = None,
    ) -> None:
        self.plan, self.out, self.echo, self.signals = plan, out, echo, signals
        self.log_level = log_level or plan.log_level or os.environ.get("MOVER_LOG_LEVEL")
        self.seeds: Seeds = seeds(plan, seed)
        self.host = host
        if plan.hosts and host is None:
            raise UpError(f"{plan.source} places processes on hosts: say which with --host NAME")
        self.router = uses_router(plan)
        self.port = plan.port or free_port()
        self.endpoint = f"tcp/127.0.0.1:{self.port}"
        self.name = SUPERVISOR
        if host is not None:
            try:
                mine = _hosts.host_of(plan, host)
            except ConfigError as exc:
                raise UpError(str(exc)) from None
            self.router = _hosts.router_host(plan) == mine
            self.port = _hosts.router_host(plan).port
            self.endpoint = _hosts.endpoint(plan)
            self.name = _hosts.supervisor(host)
        self.team, self.key_source = team_of(plan)
        if host is not None and self.key_source == "fresh":
            raise UpError(
                f"a team across hosts needs one key on every host: key_file in [team] of "
                f"{plan.source}, or MOVER_TEAM_KEY / MOVER_TEAM_KEY_FILE"
            )
        self.node: Node = None  # type: ignore[assignment]  # set on entry
        self.children: list[_Child] = []
        self.t0 = time.monotonic()
        self._fault: asyncio.Future[ProcessExited] | None = None
        self._stop = asyncio.Event()
        self._signals = 0
        self._tasks: set[asyncio.Task[Any]] = set()
        self._width = 0

    # -- life ------------------------------------------------------------------------------------

    async def __aenter__(self) -> Self:
        loop = asyncio.get_running_loop()
        self._fault = loop.create_future()
        if self.signals:
            for sig in (signal.SIGINT, signal.SIGTERM):
                loop.add_signal_handler(sig, self._on_signal, sig)
        return await super().__aenter__()

    async def _start(self) -> None:
        try:
            procs = processes(self.plan, self.seeds, self.out, port=self.port, host=self.host)
        except ConfigError as exc:
            raise UpError(str(exc)) from None
        self._width = max((len(p.name) for p in procs), default=0) + 2
        data = resolved(self.plan, self.seeds, procs, self.router)
        try:
            self.out.mkdir(parents=True, exist_ok=True)
            (self.out / "team.json").write_text(json.dumps(data, indent=2) + "\n")
            if self.key_source == "fresh":  # so that a terminal of one's own can join the team
                key = self.out / "team.key"
                key.touch(mode=0o600)
                key.write_text(self.team.key.hex() + "\n")
                self.key_source = f"fresh, in {key}"
        except OSError as exc:
            raise UpError(
                f"cannot write the run folder {self.out}: {exc.strerror or exc}"
            ) from None
        endpoint = self.endpoint
        if self.host is not None:
            theirs = NodeConfig(mode="client", listen=(), connect=(endpoint,))
            try:
                mine = _hosts.member_config(self.plan, self.name)
            except ConfigError as exc:
                raise UpError(str(exc)) from None
        elif self.router:
            mine = NodeConfig(mode="client", listen=(), connect=(endpoint,))
            theirs = mine
        else:
            mine = NodeConfig(listen=(endpoint,))
            theirs = NodeConfig(connect=(endpoint,))
        env = self._env(theirs)
        rest = procs
        if self.router:  # it must listen before anyone connects as its client
            router = await self._spawn(procs[0], env)
            await self.guard(
                asyncio.wait_for(router.said_ready.wait(), ROUTER_READY), "the router to listen"
            )
            rest = procs[1:]
        hint = ""
        if self.host is not None:
            home = _hosts.router_host(self.plan).name
            hint = f"is `mover up {self.plan.source} --host {home}` running?"
        self.node = Node(self.name, self.team, kind="tool", config=mine, reach_hint=hint)
        await self._join(endpoint)
        for p in rest:
            child = await self._spawn(p, env)
            if not p.member and p.ready_line:  # not a member: ready once it says so
                await self._said_ready(child)

    async def _said_ready(self, child: _Child) -> None:
        """Wait, bounded, for a process that is no member (an Aseba Playground) to print its
        ready line: the processes started after it need what it serves."""
        bound = self.ready_bound()
        what = f"{child.plan.ready_line!r} from {child.plan.name} within {bound:g} s"
        try:
            await self.guard(asyncio.wait_for(child.said_ready.wait(), bound))
        except TimeoutError:
            raise UpError(f"no {what} (see {self.out / child.plan.name}.log)") from None
        child.ready = True

    async def _join(self, endpoint: str) -> None:
        """Open this process's node. Across hosts the router may not be up yet: the node tries
        again, saying every few seconds which `mover up` should be running, up to the ready
        bound."""
        try:
            async with asyncio.timeout(self.ready_bound() if self.host is not None else None):
                await self.node.open()
        except TimeoutError:
            raise UpError(
                f"cannot join the team on {endpoint}: no answer in {self.ready_bound():g} s"
            ) from None
        except MoverError as exc:  # a port taken, an endpoint refused: zenoh's words
            raise UpError(f"cannot join the team on {endpoint}: {exc}") from None

    def ready_bound(self) -> float:
        """Seconds the team has to come up: the file's ``ready_timeout``, else 30 s and 2 s a
        process."""
        n = len(self.plan.members) + (self.plan.world is not None) + 1
        return self.plan.ready_timeout or min(MAX_WAIT, 30.0 + 2.0 * n)

    def _env(self, config: NodeConfig) -> dict[str, str]:
        # the team's own key and endpoints, not those of a team this shell may be set up for
        dropped = ("MOVER_TEAM_KEY_FILE", "MOVER_ZENOH_CONFIG")
        env = {k: v for k, v in os.environ.items() if k not in dropped}
        level = self.log_level or "WARNING"
        return {
            **env,
            **self.team.env(),
            **config.env(),
            "MOVER_LOG_LEVEL": level,
            "PYTHONUNBUFFERED": "1",
            **({"MOVER_PATIENCE": f"{p:g}"} if (p := self.plan.patience) is not None else {}),
        }

    async def _spawn(self, p: ProcessPlan, env: dict[str, str]) -> _Child:
        log = _open_log(self.out / f"{p.name}.log")
        env = {**env, **p.env}
        try:  # its own session: a terminal's Ctrl-C is ours to pass on, in order
            process = await start(p.name, p.argv, env=env, log=log, pump=True, own_session=True)
        except OSError as exc:
            raise UpError(f"cannot start {p.name}: {exc.strerror or exc}") from None
        child = _Child(p, process)
        self.children.append(child)
        self.say(f"started {p.name} (pid {process.proc.pid})")
        self._keep(self._watch(child))
        return child

    def _keep(self, work: Awaitable[None]) -> None:
        task = asyncio.ensure_future(work)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _watch(self, child: _Child) -> None:
        """Pump the child's lines until its output ends, then tell how it ended."""
        prefix = f"[{child.plan.name}]".ljust(self._width)

        def heard(text: str) -> None:
            if child.plan.ready_line and text.startswith(child.plan.ready_line):
                child.said_ready.set()
            if self.echo:
                _line(f"{prefix} {text}")

        code = await child.process.pump(heard)
        if self._stop.is_set():
            return
        what = f"exited with code {code}" if code >= 0 else f"was killed by signal {-code}"
        self.say(f"{child.plan.name} {what}")
        if child.plan.required or not child.ready:
            self._fail(child.process.exited(code))

    def _fail(self, fault: ProcessExited) -> None:
        if self._fault is not None and not self._fault.done():
            self._fault.set_result(fault)

    def _on_signal(self, sig: int) -> None:
        self._signals += 1
        if self._signals == 1:
            name = "Ctrl-C" if sig == signal.SIGINT else signal.Signals(sig).name
            self.say(f"{name}: stopping the team", force=True)
            self._stop.set()
        else:  # asked twice: no more patience
            for c in self.children:
                c.process.signal(signal.SIGKILL)

    def say(self, text: str, *, force: bool = False) -> None:
        """A line of ``mover up``'s own, prefixed ``[up]`` (only with ``echo``, or ``force``)."""
        if self.echo or force:
            _line(f"[{SUPERVISOR}] {text}")

    # -- waiting -----------------------------------------------------------------------------------

    async def guard(self, work: Awaitable[_T], what: str = "") -> _T:
        """Await ``work`` unless a process fails or a stop is asked first (then raise
        :class:`ProcessExited` or :class:`Stopped`). With ``what``, a TimeoutError of ``work``
        becomes an :class:`UpError` saying what was waited for."""
        assert self._fault is not None
        task = asyncio.ensure_future(work)
        stop = asyncio.ensure_future(self._stop.wait())
        try:
            await asyncio.wait({task, stop, self._fault}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            stop.cancel()
        if not task.done():
            task.cancel()
            with contextlib.suppress(BaseException):
                await task
            if self._fault.done():
                raise self._fault.result()
            raise Stopped()
        if what:
            try:
                return task.result()
            except TimeoutError:
                raise UpError(f"no {what} within the time allowed") from None
        return task.result()

    async def wait_ready(self) -> float:
        """Wait (bounded by the file's ``ready_timeout``) until every process of the team is a
        member; return the seconds it took. Raises :class:`UpError` naming who is missing."""
        names = [c.plan.name for c in self.children if c.plan.member]
        if self.host is not None:  # every host's processes: readiness is the whole team's
            names = [m.name for m in self.plan.members]
            names += [self.plan.world.name] if self.plan.world is not None else []
        bound = self.ready_bound()
        try:
            await self.guard(self.node.membership.wait_for(names, timeout=bound))
        except TimeoutError:
            missing = sorted(set(names) - self.node.membership.members())
            if self.host is not None:
                on = {m.name: m.host for m in self.plan.members}
                if self.plan.world is not None:
                    on[self.plan.world.name] = self.plan.world.host
                missing = [f"{n} (host {on[n]})" for n in missing]
            raise UpError(
                f"not ready within {bound:g} s: {', '.join(missing)} "
                f"did not join (see their logs in {self.out})"
            ) from None
        for c in self.children:
            c.ready = True
        took = time.monotonic() - self.t0
        return took

    async def wait_stopped(self) -> None:
        """Keep the team up until a stop is asked or a required process exits."""
        await self.guard(asyncio.Event().wait())

    # -- runs --------------------------------------------------------------------------------------

    async def launch(
        self, program: str, members: list[str], args: dict[str, Any], *, run: str
    ) -> dict[str, dict[str, Any]]:
        """:func:`mover.launch` with the run's program seed and the file's ``share`` and
        ``survivors``."""
        p = self.plan.program
        return await launch(
            self.node,
            program,
            members,
            args,
            run=run,
            seed=self.seeds.program,
            share=p is not None and p.share,
            policy="survivors" if p is not None and p.survivors else "fail",
        )

    # -- stopping ----------------------------------------------------------------------------------

    async def aclose(self) -> None:
        """Stop every process and close the node: the members first, then the world, then
        (once this node has closed) the router; each stage bounded by ``STOP_GRACE + 2 *
        KILL_GRACE``."""
        self._stop.set()  # from now on an exit is expected (a second Ctrl-C kills: _on_signal)
        t0 = time.monotonic()
        # A process that is not serving yet may be importing, where SIGINT is a traceback:
        # it gets SIGTERM (it has nothing to close yet).
        team = self.node.membership.members() if self.node is not None else frozenset()
        for c in self.children:
            c.ready = c.said_ready.is_set() or c.plan.name in team
            c.process.interruptible = c.ready
        ladder = _stop_ladder()
        for stage in (2, 1):
            await stop([c.process for c in self.children if c.plan.stage == stage], ladder)
        if self.node is not None:
            with contextlib.suppress(Exception):
                await self.node.close()
        await stop([c.process for c in self.children if c.plan.stage == 0], ladder)
        if self._tasks:
            await asyncio.wait(self._tasks, timeout=KILL_GRACE)
        if self.signals:
            loop = asyncio.get_running_loop()
            for sig in (signal.SIGINT, signal.SIGTERM):
                loop.remove_signal_handler(sig)
        if self.children:
            self.say(f"stopped {len(self.children)} processes in {time.monotonic() - t0:.1f} s")


def _stop_ladder() -> list[tuple[int, float]]:
    """SIGINT, SIGTERM after ``STOP_GRACE`` s, SIGKILL after ``KILL_GRACE`` more (read now)."""
    return [(signal.SIGINT, STOP_GRACE), (signal.SIGTERM, KILL_GRACE), (signal.SIGKILL, KILL_GRACE)]


_quiet = False  # standard output went away (a closed pipe): the logs still get every line


def _line(text: str) -> None:
    """Print one line of the stream, unless nobody reads it any more."""
    global _quiet
    if _quiet:
        return
    try:
        print(text, flush=True)
    except (BrokenPipeError, OSError):
        _quiet = True


def _open_log(path: Path) -> IO[bytes]:
    try:
        return path.open("ab")
    except OSError as exc:
        raise UpError(f"cannot write {path}: {exc.strerror or exc}") from None


def team_of(plan: TeamPlan) -> tuple[TeamCredentials, str]:
    """The team and where its key came from: the file's ``key_file``, the environment
    (``MOVER_TEAM_KEY`` or ``MOVER_TEAM_KEY_FILE``), else a fresh key."""
    if plan.key_file is not None:
        try:
            text = plan.key_file.read_text().strip()
        except OSError as exc:
            raise UpError(
                f"cannot read the key file {plan.key_file}: {exc.strerror or exc}"
            ) from None
        try:
            return TeamCredentials(plan.name, bytes.fromhex(text)), f"from {plan.key_file}"
        except ValueError as exc:
            raise UpError(f"the key file {plan.key_file}: not a hex key ({exc})") from None
    if os.environ.get("MOVER_TEAM_KEY") or os.environ.get("MOVER_TEAM_KEY_FILE"):
        try:
            return TeamCredentials.from_env(plan.name), "from the environment"
        except ValueError as exc:
            raise UpError(str(exc)) from None
    return TeamCredentials.generate(plan.name), "fresh"
