"""The wire format: msgpack envelopes, numpy arrays, HMAC authentication and replay refusal.

A signed frame is ``b"M1" + body + tag`` where ``body`` is the msgpack array
``[version, team, sender, kind, call_id, timestamp, nonce, payload]`` and ``tag`` is the 32-byte
HMAC-SHA256 of ``body`` under the team's key. ``timestamp`` is Unix time in seconds (float);
``nonce`` is 16 bytes: the sender's random 8-byte epoch (new each time a node opens) and a
big-endian 8-byte counter. A refusal, sent to a caller that could not be authenticated, is the
unsigned frame ``b"MR" + reason`` (UTF-8).

numpy arrays travel as msgpack extension type 1 whose data is::

    u8 len(dtype) | dtype.str (ASCII, e.g. "<f8") | u8 ndim | ndim x u64 LE shape | raw bytes

(the raw bytes in C order).

Only numeric and boolean dtypes are carried (no object arrays: nothing is ever unpickled).
Tuples arrive as lists.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import struct
import time
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np

from ._exceptions import PayloadTooLarge, WireError

VERSION = 1
SIGNED = b"M1"
REFUSAL = b"MR"
TAG_SIZE = 32
DEFAULT_MAX_SIZE = 4 * 1024 * 1024
NDARRAY_EXT = 1
_NUMERIC_KINDS = frozenset("biufc")


def _default(obj: object) -> Any:
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _NUMERIC_KINDS:
            raise WireError(f"cannot send a numpy array of dtype {obj.dtype}")
        dtype = obj.dtype.str.encode("ascii")
        head = struct.pack(f"<B{len(dtype)}sB{obj.ndim}Q", len(dtype), dtype, obj.ndim, *obj.shape)
        return msgpack.ExtType(NDARRAY_EXT, head + np.ascontiguousarray(obj).tobytes())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    raise WireError(f"cannot send a value of type {type(obj).__name__}")


def _ext_hook(code: int, data: bytes) -> Any:
    if code != NDARRAY_EXT:
        raise WireError(f"unknown extension type {code}")
    n = data[0]
    dtype = np.dtype(data[1 : 1 + n].decode("ascii"))
    if dtype.kind not in _NUMERIC_KINDS:
        raise WireError(f"refusing numpy dtype {dtype}")
    ndim = data[1 + n]
    start = 2 + n + 8 * ndim
    shape = struct.unpack_from(f"<{ndim}Q", data, 2 + n)
    return np.frombuffer(data, dtype=dtype, offset=start).reshape(shape).copy()


def pack(value: Any) -> bytes:
    """Encode a value with mover's msgpack conventions (numpy arrays as extension type 1)."""
    try:
        return msgpack.packb(value, default=_default, use_bin_type=True)  # type: ignore[no-any-return]
    except WireError:
        raise
    except (TypeError, ValueError, OverflowError) as exc:
        raise WireError(f"cannot encode value: {exc}") from exc


def unpack(data: bytes, *, max_size: int = DEFAULT_MAX_SIZE) -> Any:
    """Decode what :func:`pack` made; raise :class:`WireError` on anything malformed."""
    if len(data) > max_size:
        raise PayloadTooLarge(f"{len(data)} bytes is over the limit of {max_size}")
    try:
        return msgpack.unpackb(
            data,
            ext_hook=_ext_hook,
            raw=False,
            strict_map_key=False,
        )
    except WireError:
        raise
    except Exception as exc:  # msgpack raises several unrelated types on bad input
        raise WireError(f"malformed msgpack: {exc}") from exc


@dataclass(frozen=True, slots=True)
class Envelope:
    """One authenticated message."""

    team: str
    sender: str
    kind: str
    call_id: int
    timestamp: float
    nonce: bytes
    payload: Any
    version: int = VERSION


class Sealer:
    """Signs outgoing envelopes for one sender under a team key."""

    def __init__(self, team: str, sender: str, key: bytes, *, max_size: int = DEFAULT_MAX_SIZE):
        self.team = team
        self.sender = sender
        self._key = key
        self._epoch = os.urandom(8)
        self._counter = 0
        self.max_size = max_size

    def seal(self, kind: str, payload: Any, call_id: int = 0) -> bytes:
        """Return the signed frame of a new envelope; raise PayloadTooLarge over the limit."""
        return self.seal_packed(kind, pack(payload), call_id)

    def seal_packed(self, kind: str, payload: bytes, call_id: int = 0) -> bytes:
        """Like :meth:`seal` for a payload already encoded with :func:`pack`."""
        self._counter += 1
        nonce = self._epoch + self._counter.to_bytes(8, "big")
        head = pack([VERSION, self.team, self.sender, kind, call_id, time.time(), nonce])
        body = b"\x98" + head[1:] + payload  # the same fields as an 8-element array
        if len(body) + TAG_SIZE + 2 > self.max_size:
            raise PayloadTooLarge(
                f"{kind} envelope of {len(body)} bytes is over the limit of {self.max_size}"
            )
        return SIGNED + body + hmac.digest(self._key, body, hashlib.sha256)


class ReplayGuard:
    """Refuses envelopes that are stale or seen before.

    Each sender epoch keeps the highest counter seen and a bitmap of the last ``window`` counters
    (as IPsec does), so envelopes that arrive a little out of order across zenoh's threads pass
    once. Envelopes older than ``max_age`` seconds (or that far in the future) are refused
    outright, which bounds how long an epoch must be remembered.
    """

    def __init__(self, *, max_age: float = 30.0, window: int = 4096) -> None:
        self.max_age = max_age
        self.window = window
        self._epochs: dict[bytes, list[Any]] = {}  # epoch -> [highest, bitmap, last_seen]
        self._next_prune = 0.0

    def check(self, env: Envelope, now: float | None = None) -> str | None:
        """Record the envelope; return why it is refused, or None if it is fresh."""
        now = time.time() if now is None else now
        if abs(now - env.timestamp) > self.max_age:
            return f"stale timestamp ({now - env.timestamp:+.1f} s)"
        if len(env.nonce) != 16:
            return "malformed nonce"
        epoch, counter = env.nonce[:8], int.from_bytes(env.nonce[8:], "big")
        state = self._epochs.get(epoch)
        if state is None:
            self._epochs[epoch] = [counter, 1, now]
        else:
            highest, bitmap = state[0], state[1]
            if counter > highest:
                bitmap = ((bitmap << (counter - highest)) | 1) & ((1 << self.window) - 1)
                state[0] = counter
            else:
                offset = highest - counter
                if offset >= self.window:
                    return "replayed (too old for the window)"
                if bitmap >> offset & 1:
                    return "replayed nonce"
                bitmap |= 1 << offset
            state[1] = bitmap
            state[2] = now
        if now >= self._next_prune:
            self._prune(now)
        return None

    def _prune(self, now: float) -> None:
        horizon = now - 2 * self.max_age
        for epoch in [e for e, s in self._epochs.items() if s[2] < horizon]:
            del self._epochs[epoch]
        self._next_prune = now + self.max_age


class Opener:
    """Verifies and decodes incoming frames for one team."""

    def __init__(self, team: str, key: bytes, *, max_size: int = DEFAULT_MAX_SIZE) -> None:
        self.team = team
        self._key = key
        self.max_size = max_size
        self.guard = ReplayGuard()

    def open(self, frame: bytes) -> Envelope:
        """Return the envelope in a signed frame, or raise WireError saying why it is refused."""
        if len(frame) > self.max_size:
            raise PayloadTooLarge(f"frame of {len(frame)} bytes is over the limit")
        if frame[:2] != SIGNED or len(frame) < 2 + TAG_SIZE + 8:
            raise WireError("not a signed mover frame")
        body, tag = frame[2:-TAG_SIZE], frame[-TAG_SIZE:]
        if not hmac.compare_digest(hmac.digest(self._key, body, hashlib.sha256), tag):
            raise WireError("bad signature (no key, or another team's key)")
        fields = unpack(body, max_size=self.max_size)
        if not isinstance(fields, list) or len(fields) != 8:
            raise WireError("envelope is not an 8-field array")
        version, team, sender, kind, call_id, timestamp, nonce, payload = fields
        if version != VERSION:
            raise WireError(f"unsupported envelope version {version!r}")
        if team != self.team:
            raise WireError(f"envelope for team {team!r}")
        if not (
            isinstance(sender, str)
            and isinstance(kind, str)
            and isinstance(call_id, int)
            and isinstance(timestamp, (int, float))
            and isinstance(nonce, bytes)
        ):
            raise WireError("envelope fields have wrong types")
        env = Envelope(team, sender, kind, call_id, float(timestamp), nonce, payload)
        why = self.guard.check(env)
        if why is not None:
            raise WireError(f"refused envelope from {sender!r}: {why}")
        return env


def refusal(reason: str) -> bytes:
    """An unsigned refusal frame for a caller that could not be authenticated."""
    return REFUSAL + reason.encode("utf-8", "replace")[:200]


def read_refusal(frame: bytes) -> str | None:
    """The reason in a refusal frame, or None if the frame is not one."""
    if frame[:2] == REFUSAL:
        return frame[2:].decode("utf-8", "replace")
    return None
