"""One Aseba node over a byte stream (TCP to a Playground robot or a switch, or a serial port).

Owns the connection: opening it (``tcp:HOST:PORT``, or the path of a serial device such as
``/dev/ttyACM0``), the handshake (find the node, learn its variable table), reading and setting
variables by name, and noticing the node going away. One reader task takes every message off
the stream; a request for variables waits for its answer with a bounded timeout. Anything that
ends the conversation (the stream closed, a read or write that failed, an answer that did not
come in time) is :class:`~robots.hal.HardwareLost`, said in one line, and every waiter gets it.

Cost: one ``GET_VARIABLES`` and its ``VARIABLES`` answer per span read (about 30 bytes each
way for the Thymio's sensors), and one ``SET_VARIABLES`` per variable set.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import termios
import tty
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

from mover._futures import failure
from robots.hal import HardwareLost

from . import _aseba as aseba

log = logging.getLogger("robots.thymio")

HOST = 1
"""The node id this host sends as (as Aseba Studio and thymiodirect do)."""


@dataclass(frozen=True, slots=True)
class Address:
    """Where a Thymio is: ``tcp:HOST:PORT`` (``host``, ``port``) or a serial ``device``."""

    host: str = ""
    port: int = 0
    device: str = ""

    @classmethod
    def parse(cls, text: str) -> Address:
        """``tcp:HOST:PORT``, ``tcp:PORT`` (on 127.0.0.1), or a device path; ValueError else."""
        if text.startswith("tcp:"):
            host, _, port = text[4:].rpartition(":")
            try:
                number = int(port)
            except ValueError:
                number = -1
            if not 0 < number < 65536:
                raise ValueError(f"link {text!r}: expected tcp:HOST:PORT with a port number")
            return cls(host=host or "127.0.0.1", port=number)
        if text.startswith("/"):
            return cls(device=text)
        raise ValueError(f"link {text!r}: expected tcp:HOST:PORT or a serial device path")

    def __str__(self) -> str:
        return f"tcp:{self.host}:{self.port}" if self.device == "" else self.device


_DESCRIBING = (
    aseba.NODE_PRESENT,
    aseba.DESCRIPTION,
    aseba.NAMED_VARIABLE,
    aseba.LOCAL_EVENT,
    aseba.NATIVE_FUNCTION,
)


class AsebaLink:
    """A conversation with one Aseba node: its variables by name (see the module docstring).

    Build it with :meth:`open`; ``variables`` maps each named variable to (offset, size).
    """

    def __init__(self, address: Address, reader: asyncio.StreamReader, writer: _Writer) -> None:
        self.address = address
        self.node = -1
        self.name = ""
        self.variables: dict[str, tuple[int, int]] = {}
        self.table_size = 0
        self.farewell: tuple[aseba.Message, ...] = ()
        """Sent as the link is closed by this side (the process ending): stop the motors."""
        self.events: list[str] = []
        self.natives: list[str] = []
        self._reader = reader
        self._writer = writer
        self._inbox: asyncio.Queue[aseba.Message | None] = asyncio.Queue()
        self._waiting: dict[int, list[asyncio.Future[tuple[int, ...]]]] = {}
        self._lost: HardwareLost | None = None
        self._task = asyncio.get_running_loop().create_task(self._read())
        self._task.add_done_callback(failure)

    @classmethod
    async def open(cls, address: Address, node: int | None, timeout: float) -> AsebaLink:
        """Connect to ``address`` and shake hands with ``node`` (None: the first that answers).

        HardwareLost if nothing listens there, or no node answers within ``timeout`` seconds.
        """
        try:
            async with asyncio.timeout(timeout):
                reader, writer = await _open_stream(address)
        except (OSError, TimeoutError) as exc:
            raise HardwareLost(f"no Thymio at {address}: {_why(exc)}") from None
        link = cls(address, reader, writer)
        try:
            async with asyncio.timeout(timeout):
                await link._handshake(node)
        except TimeoutError:
            await link.aclose()
            raise HardwareLost(
                f"no Aseba node answered at {address} within {timeout:g} s"
            ) from None
        except BaseException:
            await link.aclose()
            raise
        return link

    async def _handshake(self, node: int | None) -> None:
        while self.node < 0:  # asked again: a Playground just up may miss the first
            self._send(aseba.list_nodes(HOST))
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(0.5):
                    while True:
                        msg = await self._next()
                        if msg.type == aseba.NODE_PRESENT and node in (None, msg.source):
                            self.node = msg.source
                            break
        self._send(aseba.get_node_description(HOST, self.node))
        head: aseba.Description | None = None
        offset = 0
        while head is None or (
            len(self.variables) < head.variables
            or len(self.events) < head.events
            or len(self.natives) < head.natives
        ):
            msg = await self._next()
            if msg.source != self.node:
                continue
            if msg.type == aseba.DESCRIPTION:
                head = aseba.decode_description(msg.payload)
                self.name = head.name
            elif head is None:
                continue
            elif msg.type == aseba.NAMED_VARIABLE:
                name, size = aseba.decode_named_variable(msg.payload)
                self.variables[name] = (offset, size)
                offset += size
            elif msg.type == aseba.LOCAL_EVENT:
                self.events.append(aseba.decode_name(msg.payload))
            elif msg.type == aseba.NATIVE_FUNCTION:
                self.natives.append(aseba.decode_name(msg.payload))
        self.table_size = offset

    async def _next(self) -> aseba.Message:
        # A plain Queue.get: cancelled (a handshake's timeout), it takes nothing from the
        # queue, so the next call gets the next message (a getter task left behind would not).
        msg = await self._inbox.get()
        if msg is None:  # the link ended (see _lose)
            self._check()
            raise HardwareLost(f"the Thymio at {self.address} closed the link")
        return msg

    def require(self, names: Iterable[str]) -> None:
        """HardwareLost naming what is missing unless the node has every variable of ``names``
        (a node that is not a Thymio II, or firmware of another kind)."""
        missing = sorted(set(names) - set(self.variables))
        if missing:
            raise HardwareLost(
                f"node {self.node} ({self.name!r}) at {self.address} has no variable "
                f"{', '.join(missing)}: not a Thymio II"
            )

    async def read(self, start: int, length: int, timeout: float) -> tuple[int, ...]:
        """``length`` words of the variable table from ``start``; HardwareLost if no answer
        comes within ``timeout`` seconds."""
        self._check()
        answer: asyncio.Future[tuple[int, ...]] = asyncio.get_running_loop().create_future()
        self._waiting.setdefault(start, []).append(answer)
        self._send(aseba.get_variables(HOST, self.node, start, length))
        try:
            async with asyncio.timeout(timeout):
                values = await answer
        except TimeoutError:
            self._lose(HardwareLost(f"the Thymio at {self.address} did not answer in {timeout} s"))
            raise self._lost from None  # type: ignore[misc]
        finally:
            with contextlib.suppress(ValueError):
                self._waiting.get(start, []).remove(answer)
        return values[:length]

    def write(self, name: str, values: tuple[int, ...]) -> None:
        """Set variable ``name`` (from its first word) to ``values``."""
        self.write_at(self.variables[name][0], values)

    def write_at(self, start: int, values: tuple[int, ...]) -> None:
        """Set the variable table from word ``start`` to ``values``."""
        self._check()
        self._send(aseba.set_variables(HOST, self.node, start, values))

    def load(self, bytecode: tuple[int, ...]) -> None:
        """Load ``bytecode`` into the node and run it."""
        self._check()
        self._send(aseba.set_bytecode(HOST, self.node, 0, bytecode))
        self._send(aseba.run(HOST, self.node))

    def _send(self, msg: aseba.Message) -> None:
        try:
            self._writer.write(msg.encode())
        except (OSError, RuntimeError) as exc:
            self._lose(HardwareLost(f"the Thymio at {self.address} is gone: {_why(exc)}"))
            self._check()

    def _check(self) -> None:
        if self._lost is not None:
            raise self._lost

    @property
    def lost(self) -> HardwareLost | None:
        """Why the link ended, or None while it lasts."""
        return self._lost

    async def wait_lost(self) -> HardwareLost:
        """Return (not raise) the HardwareLost that ends the link, when it does."""
        await asyncio.wait([self._task])
        assert self._lost is not None
        return self._lost

    async def _read(self) -> None:
        buffer = bytearray()
        try:
            while True:
                chunk = await self._reader.read(4096)
                if not chunk:
                    raise HardwareLost(f"the Thymio at {self.address} closed the link")
                buffer += chunk
                for msg in aseba.split(buffer):
                    self._dispatch(msg)
        except HardwareLost as exc:
            self._lose(exc)
        except (OSError, ValueError) as exc:
            self._lose(HardwareLost(f"the link to the Thymio at {self.address}: {_why(exc)}"))
        except asyncio.CancelledError:
            if self._lost is None:  # closed by this side, the robot still there: farewell
                for msg in self.farewell:
                    with contextlib.suppress(OSError, RuntimeError):
                        self._writer.write(msg.encode())
            raise
        finally:
            self._lose(HardwareLost(f"the link to the Thymio at {self.address} was closed"))
            self._writer.close()  # the stream ends with its reader
            with contextlib.suppress(Exception):  # (a reset was said already: _lose)
                await self._writer.wait_closed()

    def _dispatch(self, msg: aseba.Message) -> None:
        if msg.type == aseba.VARIABLES and msg.source == self.node:
            start, values = aseba.decode_variables(msg.payload)
            waiters = self._waiting.get(start)
            if waiters:
                answer = waiters.pop(0)
                if not answer.done():
                    answer.set_result(values)
        elif msg.type in _DESCRIBING:
            self._inbox.put_nowait(msg)
        # Anything else (events, execution states, other nodes' traffic) is not ours.

    def _lose(self, exc: HardwareLost) -> None:
        if self._lost is not None:
            return
        self._lost = exc
        self._inbox.put_nowait(None)  # wakes a handshake under way
        for waiters in self._waiting.values():
            for answer in waiters:
                if not answer.done():
                    answer.set_exception(exc)
        self._waiting.clear()

    async def aclose(self) -> None:
        """Close the stream and end the reader."""
        self._task.cancel()
        await asyncio.gather(self._task, return_exceptions=True)


async def list_nodes(address: Address, wait: float = 1.0) -> dict[int, str]:
    """The Aseba nodes that answer at ``address`` within ``wait`` seconds: id → name (the
    ids to give as ``node`` when several robots share one link, as behind ``asebaswitch``).
    HardwareLost if nothing listens there."""
    try:
        async with asyncio.timeout(wait + 1.0):
            reader, writer = await _open_stream(address)
    except (OSError, TimeoutError) as exc:
        raise HardwareLost(f"no Thymio at {address}: {_why(exc)}") from None
    link = AsebaLink(address, reader, writer)
    nodes: dict[int, str] = {}
    try:
        link._send(aseba.list_nodes(HOST))
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(wait):
                while True:
                    msg = await link._next()
                    if msg.type == aseba.NODE_PRESENT and msg.source not in nodes:
                        nodes[msg.source] = ""
                        link._send(aseba.get_node_description(HOST, msg.source))
                    elif msg.type == aseba.DESCRIPTION and msg.source in nodes:
                        nodes[msg.source] = aseba.decode_description(msg.payload).name
    finally:
        await link.aclose()
    return dict(sorted(nodes.items()))


class _Writer(Protocol):
    def write(self, data: bytes) -> None: ...
    def close(self) -> None: ...
    async def wait_closed(self) -> None: ...


class _PipeWriter:
    """A serial device's write side, as a StreamWriter is used here."""

    def __init__(self, transport: asyncio.WriteTransport) -> None:
        self._transport = transport

    def write(self, data: bytes) -> None:
        self._transport.write(data)

    def close(self) -> None:
        self._transport.close()

    async def wait_closed(self) -> None:
        return None


def _why(exc: BaseException) -> str:
    if isinstance(exc, TimeoutError):
        return "no answer"
    return getattr(exc, "strerror", None) or str(exc) or type(exc).__name__


async def _open_stream(address: Address) -> tuple[asyncio.StreamReader, _Writer]:
    loop = asyncio.get_running_loop()
    if address.device == "":
        # (the StreamWriter is kept: once collected, it closes its transport)
        return await asyncio.open_connection(address.host, address.port)
    # A serial device (the Thymio's USB CDC port, or the wireless dongle's): raw mode, no
    # baud rate to speak of; asyncio reads and writes character devices as pipes.
    fd = os.open(address.device, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    with contextlib.suppress(termios.error):  # not a terminal (a pipe): nothing to set
        tty.setraw(fd, termios.TCSANOW)
    reader = asyncio.StreamReader()
    await loop.connect_read_pipe(
        lambda: asyncio.StreamReaderProtocol(reader), os.fdopen(fd, "rb", buffering=0)
    )
    write_fd = os.dup(fd)
    transport, _ = await loop.connect_write_pipe(
        asyncio.BaseProtocol, os.fdopen(write_fd, "wb", buffering=0)
    )
    return reader, _PipeWriter(transport)
