"""A fake Aseba node for the unit tests: a Thymio II's variables over any byte stream.

It answers the messages the backend sends (list nodes, describe, get and set variables, load
and run bytecode) over an asyncio stream (a TCP server's) or a file descriptor (a pty's master
side, for the serial path), alone or several on one stream (:class:`FakeBus`). Its motors
reach their targets at once: ``motor.*.speed`` reads back what ``motor.*.target`` was set to.
Each message it got is kept in ``got``.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import struct

from robots.thymio import _aseba as aseba

NODE = 7
"""The fake node's id (not 1, the host's, so that a mix-up shows)."""

#: The named variables, in table order, and their sizes (a subset of the firmware's).
VARIABLES: tuple[tuple[str, int], ...] = (
    ("_id", 1),
    ("button.backward", 1),
    ("button.left", 1),
    ("button.center", 1),
    ("button.forward", 1),
    ("button.right", 1),
    ("prox.horizontal", 7),
    ("prox.ground.delta", 2),
    ("motor.left.target", 1),
    ("motor.right.target", 1),
    ("motor.left.speed", 1),
    ("motor.right.speed", 1),
)
EVENTS = ("button.center", "buttons", "prox")
NATIVES = ("math.copy", "leds.circle", "leds.top")
LED_WORDS = sum(size for _, size in VARIABLES)
"""Where the LED program's 11 words start (past the named variables), and its copy after."""
TABLE = LED_WORDS + 22


def offset(name: str) -> int:
    """Where ``name`` starts in the fake's table."""
    at = 0
    for n, size in VARIABLES:
        if n == name:
            return at
        at += size
    raise KeyError(name)


def _string(text: str) -> bytes:
    data = text.encode()
    return bytes([len(data)]) + data


class FakeNode:
    """The node's state and its answers (see the module docstring)."""

    def __init__(self, node: int = NODE, name: str = "thymio-II") -> None:
        self.node, self.name = node, name
        self.table = [0] * TABLE
        self.table[offset("prox.ground.delta")] = 900  # a white floor
        self.table[offset("prox.ground.delta") + 1] = 900
        self.got: list[aseba.Message] = []
        self.bytecode: tuple[int, ...] = ()

    def set(self, name: str, *values: int) -> None:
        """Set variable ``name`` from its first word (as the robot's sensors do)."""
        at = offset(name)
        self.table[at : at + len(values)] = values

    def get(self, name: str) -> int:
        """The first word of variable ``name``."""
        return self.table[offset(name)]

    def answer(self, msg: aseba.Message) -> bytes:
        """What the node sends back for ``msg`` (nothing: b"")."""
        self.got.append(msg)
        words = struct.unpack(f"<{len(msg.payload) // 2}H", msg.payload[: len(msg.payload) & ~1])
        if msg.type == aseba.LIST_NODES:
            return aseba.Message(aseba.NODE_PRESENT, self.node, struct.pack("<H", 5)).encode()
        addressed = (aseba.SET_BYTECODE, aseba.RUN, aseba.GET_VARIABLES, aseba.SET_VARIABLES)
        if msg.type in addressed and words[0] != self.node:
            return b""  # another node's
        if msg.type == aseba.GET_NODE_DESCRIPTION and words[0] == self.node:
            return self._description()
        if msg.type == aseba.SET_BYTECODE:
            self.bytecode = tuple(words[2:])
        elif msg.type == aseba.SET_VARIABLES:
            start = words[1]
            values = struct.unpack(f"<{len(words) - 2}h", msg.payload[4:])
            self.table[start : start + len(values)] = values
            for side in ("left", "right"):  # the motors reach their targets at once
                self.set(f"motor.{side}.speed", self.get(f"motor.{side}.target"))
            if self.bytecode:  # the LED program applies the lights and copies what it did
                self.table[LED_WORDS + 11 : TABLE] = self.table[LED_WORDS : LED_WORDS + 11]
        elif msg.type == aseba.GET_VARIABLES:
            start, length = words[1], words[2]
            payload = struct.pack(f"<H{length}h", start, *self.table[start : start + length])
            return aseba.Message(aseba.VARIABLES, self.node, payload).encode()
        return b""

    def _description(self) -> bytes:
        head = _string(self.name) + struct.pack(
            "<7H", 5, 1536, 32, TABLE, len(VARIABLES), len(EVENTS), len(NATIVES)
        )
        out = [aseba.Message(aseba.DESCRIPTION, self.node, head)]
        out += [
            aseba.Message(aseba.NAMED_VARIABLE, self.node, struct.pack("<H", size) + _string(n))
            for n, size in VARIABLES
        ]
        out += [
            aseba.Message(aseba.LOCAL_EVENT, self.node, _string(e) + _string("")) for e in EVENTS
        ]
        out += [
            aseba.Message(  # name, description, no parameters
                aseba.NATIVE_FUNCTION, self.node, _string(n) + _string("") + struct.pack("<H", 0)
            )
            for n in NATIVES
        ]
        return b"".join(m.encode() for m in out)

    def feed(self, buffer: bytearray) -> bytes:
        """Take the whole messages off ``buffer``; the answers to them."""
        return b"".join(self.answer(msg) for msg in aseba.split(buffer))


class FakeBus:
    """Fake nodes on one stream, as the nodes paired with one wireless dongle are: every
    message reaches each of them, each answers its own."""

    def __init__(self, *nodes: FakeNode) -> None:
        self.nodes = nodes

    def feed(self, buffer: bytearray) -> bytes:
        """Take the whole messages off ``buffer``; every node's answers to them."""
        return b"".join(node.answer(msg) for msg in aseba.split(buffer) for node in self.nodes)

    async def serve_stream(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        """Serve one connection (an ``asyncio.start_server`` callback)."""
        buffer = bytearray()
        try:
            while chunk := await reader.read(4096):
                buffer += chunk
                writer.write(self.feed(buffer))
        finally:
            writer.close()

    async def serve_fd(self, fd: int) -> None:
        """Serve the file descriptor ``fd`` (a pty's master) until it ends or the task is
        cancelled; ``fd`` is left open (the caller closes it: the cable pulled)."""
        loop = asyncio.get_running_loop()
        readable = asyncio.Event()
        loop.add_reader(fd, readable.set)
        buffer = bytearray()
        try:
            while True:
                await readable.wait()
                readable.clear()
                try:
                    chunk = os.read(fd, 4096)
                except BlockingIOError:
                    continue
                except OSError:  # EIO: the other side closed
                    return
                if not chunk:
                    return
                buffer += chunk
                out = self.feed(buffer)
                while out:
                    with contextlib.suppress(BlockingIOError):
                        out = out[os.write(fd, out) :]
        finally:
            loop.remove_reader(fd)
