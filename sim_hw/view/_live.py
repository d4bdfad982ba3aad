"""The live view: an observer of the team that draws a running world into rerun.

It is a node with no liveliness token (``Node(observer=True)``): not a member, so a team's
programs, ``mover ps`` and the world's joins never see it, and any number of views can watch
one world. For each world session (from the world's appearance in the team to its leaving) it
asks the world for its scene (``view.scene``), opens a new rerun recording, and then draws:

* the pymunk world from its state topic (``world/state``: the world's own snapshots, at the
  rate of ``mover world --state-rate``), only what the world itself sent, at most
  :data:`MAX_RATE` frames a wall second (a lock-step world can run far faster than real time);
* a grid world by asking ``view.frame`` :data:`GRID_RATE` times a wall second (a grid world
  streams no state), drawing only rounds it has not drawn.

A world that leaves is said once, and waited for; when it (or another world of that name)
comes back, a new recording starts (the browser shows the newest).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import rerun as rr

from mover import CallError, MoverError, Node, NodeConfig, TeamCredentials
from sim_hw._process import STATE_TOPIC

from ._entities import Drawing, log_entities, log_frame
from ._scene import FRAME, SCENE

log = logging.getLogger("sim_hw.view")

GRID_RATE = 5.0
"""Grid frames asked for per wall second."""

MAX_RATE = 30.0
"""State frames drawn per wall second at most: a lock-step world may run many times faster
than real time, and a browser shows no more (the newest is drawn, those before it skipped)."""

STATE_QUEUE = 2_000
"""State messages a view keeps unread at most (a slow view drops the oldest)."""

SILENT_WAIT = 2.0
"""Seconds a view looks for its world before it says it waits (the team takes a moment)."""

FLUSH_TIMEOUT = 5.0
"""Seconds a recording has to send what is left when it closes."""

CALL_TIMEOUT = 5.0
"""Seconds a world has to answer a view's call."""


def open_recording(
    name: str, drawing: Drawing, *, grpc_url: str | None, save: Path | None, live: bool = True
) -> rr.RecordingStream:
    """A new rerun recording of one world session, sent to the server and/or saved to a file,
    its blueprint and static scene already logged."""
    rec = rr.RecordingStream("mover", recording_id=uuid.uuid4(), send_properties=False)
    sinks: list[Any] = []
    if grpc_url is not None:
        sinks.append(rr.GrpcSink(grpc_url))
    if save is not None:
        sinks.append(rr.FileSink(str(save)))
    blueprint = drawing.blueprint(live=live)
    rec.set_sinks(*sinks, default_blueprint=blueprint)
    rec.send_recording_name(name)
    log_entities(rec, drawing.scene())
    return rec


def close_recording(rec: rr.RecordingStream) -> None:
    """Send what is left (for at most :data:`FLUSH_TIMEOUT` s) and let the recording go."""
    try:
        rec.flush(timeout_sec=FLUSH_TIMEOUT)
    except Exception as exc:  # the server went first: nothing more to send it
        log.info("recording not flushed: %s", exc)
    rec.disconnect()


@dataclass(kw_only=True, eq=False)
class LiveView:
    """Watch world ``world`` (None: the team's world, whatever its name) and draw it.

    ``say`` prints the view's one-line news; ``grpc_url`` is the rerun server's, ``record``
    a ``.rrd`` file for the first session (later sessions get ``NAME-2.rrd``, ...).
    """

    world: str | None
    grpc_url: str | None
    record: Path | None = None
    links: float | None = None
    say: Callable[[str], None] = print
    sessions: int = field(default=0, init=False)

    async def run(self, team: TeamCredentials, config: NodeConfig) -> None:
        """Watch until cancelled."""
        name = f"view-{secrets.token_hex(3)}"
        async with Node(name, team, kind="tool", config=config, observer=True) as node:
            states = node.subscribe(STATE_TOPIC, maxlen=STATE_QUEUE)
            while True:
                world = await self._wait_for_world(node)
                try:
                    header = await node.call(world, SCENE, timeout=CALL_TIMEOUT)
                except CallError as exc:
                    self.say(f"world {world!r} gives no scene ({type(exc).__name__}); retrying")
                    await asyncio.sleep(1.0)
                    continue
                await self._session(node, world, header, states)
                self.say(f"world {world!r} is gone; waiting for it to come back")

    async def _wait_for_world(self, node: Node) -> str:
        said = False
        quiet_until = asyncio.get_running_loop().time() + SILENT_WAIT
        while True:
            found = self._find(node)
            if found is not None:
                return found
            if not said and asyncio.get_running_loop().time() > quiet_until:
                who = f"world {self.world!r}" if self.world else "a world"
                self.say(f"waiting for {who} in team {node.team_name!r}")
                said = True
            await asyncio.sleep(0.25)  # membership changes are rare: a look 4 times a second

    def _find(self, node: Node) -> str | None:
        members = node.membership.members()
        if self.world is not None:
            return self.world if self.world in members else None
        worlds = sorted(
            n for n in members if (i := node.membership.info(n)) is not None and i.kind == "world"
        )
        return worlds[0] if worlds else None

    async def _session(self, node: Node, world: str, header: Any, states: Any) -> None:
        if not isinstance(header, dict):
            self.say(f"world {world!r} sent a scene that is not one; ignoring it")
            await self._wait_gone(node, world)
            return
        self.sessions += 1
        drawing = Drawing(header, links=self.links)
        save = self._save_path()
        kind = "grid" if drawing.grid else "continuous"
        rec = open_recording(
            f"{world}: {header.get('name', world)}", drawing, grpc_url=self.grpc_url, save=save
        )
        self.say(
            f"showing world {world!r} ({header.get('name', '?')}, {kind})"
            + (f", recording to {save}" if save else "")
        )
        try:
            async with asyncio.TaskGroup() as tg:
                feed = (
                    self._poll(node, world, drawing, rec)
                    if drawing.grid
                    else self._stream(node, world, drawing, rec, states)
                )
                task = tg.create_task(feed)
                await self._wait_gone(node, world)
                task.cancel()
        finally:
            close_recording(rec)

    def _save_path(self) -> Path | None:
        if self.record is None:
            return None
        if self.sessions <= 1:
            return self.record
        return self.record.with_name(f"{self.record.stem}-{self.sessions}{self.record.suffix}")

    async def _wait_gone(self, node: Node, world: str) -> None:
        while world in node.membership.members():
            with contextlib.suppress(TimeoutError):
                await node.membership.wait_gone(world, timeout=60.0)

    async def _stream(
        self, node: Node, world: str, drawing: Drawing, rec: rr.RecordingStream, states: Any
    ) -> None:
        refused = 0
        async for first in states:
            ours = [m for m in [first, *states.drain()] if m.sender == world]
            frames = [m.data for m in ours if isinstance(m.data, dict)]
            if not frames:
                continue
            frame = frames[-1]  # the newest: those that came in between are skipped
            robots = frame.get("robots")
            if isinstance(robots, dict) and not set(robots) <= drawing.colours.keys():
                await self._rescene(node, world, drawing)  # once per new robot:
                for name in sorted(robots):
                    drawing.colour(name)  # it has its colour now, whatever the world said
            try:
                log_frame(rec, drawing, frame)
            except (KeyError, TypeError, ValueError, IndexError) as exc:
                refused += 1
                if refused == 1:
                    log.warning("a state message of %r not drawn: %r", world, exc)
            await asyncio.sleep(1.0 / MAX_RATE)  # what comes meanwhile waits in the queue

    async def _rescene(self, node: Node, world: str, drawing: Drawing) -> None:
        """A robot joined: its radius is in the world's scene now."""
        try:
            header = await node.call(world, SCENE, timeout=CALL_TIMEOUT)
        except (CallError, MoverError):
            return
        if isinstance(header, dict):
            drawing.header = header
            for name in header.get("radii", {}):
                if name != "*":
                    drawing.colour(name)

    async def _poll(
        self, node: Node, world: str, drawing: Drawing, rec: rr.RecordingStream
    ) -> None:
        last: int | None = None
        while True:
            try:
                frame = await node.call(world, FRAME, timeout=CALL_TIMEOUT)
            except (CallError, MoverError) as exc:
                log.debug("view.frame of %r: %s", world, exc)
                frame = None
            if isinstance(frame, dict) and frame.get("tick") != last:
                last = frame.get("tick")
                log_frame(rec, drawing, frame)
            await asyncio.sleep(1.0 / GRID_RATE)
