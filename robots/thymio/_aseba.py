"""The Aseba wire format: the few messages a host needs to read and set a Thymio's variables.

Pure: bytes in, bytes out, no I/O (``_link`` does the I/O). Every Aseba message is a 6-byte
header — payload length, source node, message type, each a little-endian uint16 — and the
payload, made of little-endian 16-bit words and length-prefixed strings (one byte of length,
then UTF-8). Variables are arrays of int16 in one table per node, addressed by word offset;
the node describes the table (name and size of each named variable, in table order) when a
host asks for its description. Message types and layouts are those of Aseba's
``common/msg/msg.h`` (protocol version 5 and later; the Playground of Debian's aseba 1.6.99
and the Thymio II firmware speak them). Tests pin them with real bytes.

Why not the ``thymiodirect`` package (BSD-3-Clause, EPFL): it reads in a thread of its own per
connection and hands messages to asyncio from there (a second door between threads and the
loop), calls ``asyncio.get_event_loop()`` outside a loop (a DeprecationWarning, an error under
our tests), notices a lost robot only after 3 s of silence, is untyped, and needs pyserial. The
part of the protocol a HAL needs is these seven messages.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

__all__ = [
    "DESCRIPTION",
    "GET_NODE_DESCRIPTION",
    "GET_VARIABLES",
    "LIST_NODES",
    "LOCAL_EVENT",
    "NAMED_VARIABLE",
    "NATIVE_FUNCTION",
    "NODE_PRESENT",
    "PROTOCOL_VERSION",
    "RUN",
    "SET_BYTECODE",
    "SET_VARIABLES",
    "VARIABLES",
    "Description",
    "Message",
    "decode_description",
    "decode_name",
    "decode_named_variable",
    "decode_present",
    "decode_variables",
    "get_node_description",
    "get_variables",
    "list_nodes",
    "run",
    "set_bytecode",
    "set_variables",
    "split",
]

PROTOCOL_VERSION = 5
"""The version a host announces; nodes of later versions still answer it."""

# Node → host.
DESCRIPTION = 0x9000
NAMED_VARIABLE = 0x9001
LOCAL_EVENT = 0x9002
NATIVE_FUNCTION = 0x9003
VARIABLES = 0x9005
NODE_PRESENT = 0x900C
# Host → node.
SET_BYTECODE = 0xA001
RUN = 0xA003
GET_VARIABLES = 0xA00B
SET_VARIABLES = 0xA00C
GET_NODE_DESCRIPTION = 0xA010
LIST_NODES = 0xA011

HEADER = struct.Struct("<HHH")
MAX_PAYLOAD = 512
"""Aseba's largest payload (``ASEBA_MAX_EVENT_ARG_SIZE`` is 258 bytes; 512 leaves room)."""


@dataclass(frozen=True, slots=True)
class Message:
    """One Aseba message: its type, the node that sent it, its payload."""

    type: int
    source: int
    payload: bytes

    def encode(self) -> bytes:
        """The message as it goes on the wire."""
        return HEADER.pack(len(self.payload), self.source, self.type) + self.payload


@dataclass(frozen=True, slots=True)
class Description:
    """The head of a node's description: its name, protocol version, and how many named
    variables, local events and native functions the messages after it describe."""

    name: str
    protocol: int
    variables: int
    events: int
    natives: int


def split(buffer: bytearray) -> list[Message]:
    """Take the whole messages off the front of ``buffer`` (it keeps any partial one).

    Raises ValueError for a payload longer than any Aseba message: the stream is not Aseba.
    """
    out = []
    while len(buffer) >= HEADER.size:
        length, source, kind = HEADER.unpack_from(buffer)
        if length > MAX_PAYLOAD:
            raise ValueError(f"an Aseba payload of {length} bytes: this is not an Aseba stream")
        end = HEADER.size + length
        if len(buffer) < end:
            break
        out.append(Message(kind, source, bytes(buffer[HEADER.size : end])))
        del buffer[:end]
    return out


def _words(*values: int) -> bytes:
    return struct.pack(f"<{len(values)}H", *(v & 0xFFFF for v in values))


def list_nodes(host: int) -> Message:
    """Ask every node to say it is present (``NODE_PRESENT``)."""
    return Message(LIST_NODES, host, _words(PROTOCOL_VERSION))


def get_node_description(host: int, node: int) -> Message:
    """Ask ``node`` for its description (``DESCRIPTION``, then one ``NAMED_VARIABLE`` each)."""
    return Message(GET_NODE_DESCRIPTION, host, _words(node, PROTOCOL_VERSION))


def get_variables(host: int, node: int, start: int, length: int) -> Message:
    """Ask ``node`` for ``length`` words of its variables from ``start`` (``VARIABLES``)."""
    return Message(GET_VARIABLES, host, _words(node, start, length))


def set_variables(host: int, node: int, start: int, values: tuple[int, ...]) -> Message:
    """Set ``node``'s variables from word ``start`` to ``values`` (int16 each)."""
    for v in values:
        if not -0x8000 <= v <= 0x7FFF:
            raise ValueError(f"an Aseba variable is an int16: {v} is out of range")
    return Message(SET_VARIABLES, host, _words(node, start, *values))


def _string(payload: bytes, at: int) -> tuple[str, int]:
    n = payload[at]
    return payload[at + 1 : at + 1 + n].decode("utf-8", "replace"), at + 1 + n


def decode_description(payload: bytes) -> Description:
    """A ``DESCRIPTION``: name, protocol version, bytecode, stack and variable-table sizes,
    then the counts of named variables, local events and native functions."""
    name, at = _string(payload, 0)
    protocol, _code, _stack, _table, variables, events, natives = struct.unpack_from(
        "<7H", payload, at
    )
    return Description(name, protocol, variables, events, natives)


def decode_named_variable(payload: bytes) -> tuple[str, int]:
    """A ``NAMED_VARIABLE``: (name, size in words)."""
    (size,) = struct.unpack_from("<H", payload)
    name, _ = _string(payload, 2)
    return name, size


def decode_name(payload: bytes) -> str:
    """The name a ``LOCAL_EVENT`` or a ``NATIVE_FUNCTION`` description starts with."""
    return _string(payload, 0)[0]


def set_bytecode(host: int, node: int, start: int, words: tuple[int, ...]) -> Message:
    """Load ``words`` of bytecode into ``node`` from address ``start``."""
    return Message(SET_BYTECODE, host, _words(node, start, *words))


def run(host: int, node: int) -> Message:
    """Run the bytecode loaded into ``node``."""
    return Message(RUN, host, _words(node))


def decode_variables(payload: bytes) -> tuple[int, tuple[int, ...]]:
    """A ``VARIABLES``: (start, the int16 values from there)."""
    n = len(payload) // 2
    start, *values = struct.unpack_from(f"<H{n - 1}h", payload)
    return start, tuple(values)


def decode_present(payload: bytes) -> int:
    """A ``NODE_PRESENT``: the node's protocol version."""
    return int(struct.unpack_from("<H", payload)[0])
