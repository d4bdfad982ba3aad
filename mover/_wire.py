"""The wire format: msgpack envelopes, numpy arrays, authenticated encryption, replay refusal.

A team frame is ``b"M2" + u16 header length (big-endian) + header + ciphertext``:

* ``header`` is the msgpack array ``[version, team, sender, recipient, kind, call_id,
  timestamp, nonce]``, sent in the clear and authenticated;
* ``ciphertext`` is the msgpack payload sealed with ChaCha20-Poly1305 (16-byte tag), the header
  as associated data, under a key derived for the sender's session:
  ``HKDF-SHA256(team key, salt=epoch, info=b"mover/2/" + sender)``;
* ``nonce`` is 16 bytes: the sender's random 8-byte ``epoch`` (new each time a node opens) and a
  big-endian 8-byte counter; the AEAD nonce is four zero bytes and the counter, unique under a
  session's key.

``recipient`` binds a call, a reply or a cancel to the one member it is for (empty for
broadcasts and hellos, whose topic or challenge is in the sealed payload), so that an envelope
overheard on its way to one member is refused by any other. ``timestamp`` is the sender's Unix
time. An outsider without the key sees the header (who sends what kind of message to whom, and
when), the sizes and the timing — never a payload. A refusal, sent to a caller that could not
be authenticated, is the unsigned frame ``b"MR" + reason`` (UTF-8): a caller never believes one
while an authentic answer may still come (see ``_rpc``).

numpy arrays travel as msgpack extension type 1 whose data is::

    u8 len(dtype) | dtype.str (ASCII, e.g. "<f8") | u8 ndim | ndim x u64 LE shape | raw bytes

(the raw bytes in C order).

Only numeric and boolean dtypes are carried (no object arrays: nothing is ever unpickled).
Tuples arrive as lists.
"""

from __future__ import annotations

import os
import struct
import time
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np
from cryptography.exceptions import InvalidTag
from cryptography.hazmat.primitives import hashes
from cryptography.hazmat.primitives.ciphers.aead import ChaCha20Poly1305
from cryptography.hazmat.primitives.kdf.hkdf import HKDF

from ._exceptions import PayloadTooLarge, WireError

VERSION = 2
SIGNED = b"M2"
REFUSAL = b"MR"
TAG_SIZE = 16
MAX_SESSIONS = 4096
"""Sender sessions (epochs) a receiver keeps keys and replay state for, at most."""
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
    recipient: str = ""
    version: int = VERSION


class EnvelopeRefused(WireError):
    """An authentic envelope refused all the same (replayed, stale, for someone else): the
    refuser can answer its sender with a sealed refusal, which the sender can believe."""

    def __init__(self, message: str, envelope: Envelope) -> None:
        super().__init__(message)
        self.envelope = envelope


def session_key(team_key: bytes, sender: str, epoch: bytes) -> ChaCha20Poly1305:
    """The AEAD of one sender's session (see the module docstring)."""
    hkdf = HKDF(
        algorithm=hashes.SHA256(), length=32, salt=epoch, info=b"mover/2/" + sender.encode()
    )
    return ChaCha20Poly1305(hkdf.derive(team_key))


class Sealer:
    """Seals outgoing envelopes for one sender under a team key."""

    def __init__(self, team: str, sender: str, key: bytes, *, max_size: int = DEFAULT_MAX_SIZE):
        self.team = team
        self.sender = sender
        self._epoch = os.urandom(8)
        self._aead = session_key(key, sender, self._epoch)
        self._counter = 0
        self.max_size = max_size

    def seal(self, kind: str, payload: Any, call_id: int = 0, *, to: str = "") -> bytes:
        """Return the sealed frame of a new envelope for ``to`` (empty: the team, or whoever
        asked); raise PayloadTooLarge over the limit."""
        return self.seal_packed(kind, pack(payload), call_id, to=to)

    def seal_packed(self, kind: str, payload: bytes, call_id: int = 0, *, to: str = "") -> bytes:
        """Like :meth:`seal` for a payload already encoded with :func:`pack`."""
        self._counter += 1
        counter = self._counter.to_bytes(8, "big")
        nonce = self._epoch + counter
        header = pack([VERSION, self.team, self.sender, to, kind, call_id, time.time(), nonce])
        size = 4 + len(header) + len(payload) + TAG_SIZE
        if size > self.max_size:
            raise PayloadTooLarge(
                f"{kind} envelope of {size} bytes is over the limit of {self.max_size}"
            )
        sealed = self._aead.encrypt(b"\0\0\0\0" + counter, payload, header)
        return SIGNED + len(header).to_bytes(2, "big") + header + sealed


class ReplayGuard:
    """Refuses envelopes that are stale or seen before, in bounded memory.

    Each sender epoch keeps the highest counter seen and a bitmap of the last ``window`` counters
    (as IPsec does), so envelopes that arrive a little out of order across zenoh's threads pass
    once. Envelopes older than ``max_age`` seconds (or that far in the future) are refused
    outright, which bounds how long an epoch must be remembered; at most ``sessions`` epochs
    are remembered (the least recently heard go first), and a counter that jumps ahead by more
    than the window clears the bitmap instead of growing it.
    """

    def __init__(
        self, *, max_age: float = 30.0, window: int = 4096, sessions: int = MAX_SESSIONS
    ) -> None:
        self.max_age = max_age
        self.window = window
        self.sessions = sessions
        self._mask = (1 << window) - 1
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
        state = self._epochs.pop(epoch, None)  # re-inserted last: the dict is in LRU order
        if state is None:
            state = [counter, 1, now]
        else:
            highest, bitmap = state[0], state[1]
            if counter > highest:
                shift = counter - highest
                bitmap = ((bitmap << shift) | 1) & self._mask if shift < self.window else 1
                state[0] = counter
            else:
                offset = highest - counter
                if offset >= self.window:
                    self._epochs[epoch] = state
                    return "replayed (too old for the window)"
                if bitmap >> offset & 1:
                    self._epochs[epoch] = state
                    return "replayed nonce"
                bitmap |= 1 << offset
            state[1] = bitmap
            state[2] = now
        self._epochs[epoch] = state
        while len(self._epochs) > self.sessions:
            del self._epochs[next(iter(self._epochs))]
        if now >= self._next_prune:
            self._prune(now)
        return None

    def _prune(self, now: float) -> None:
        horizon = now - 2 * self.max_age
        for epoch in [e for e, s in self._epochs.items() if s[2] < horizon]:
            del self._epochs[epoch]
        self._next_prune = now + self.max_age


class Opener:
    """Verifies, decrypts and decodes incoming frames for one team."""

    def __init__(self, team: str, key: bytes, *, max_size: int = DEFAULT_MAX_SIZE) -> None:
        self.team = team
        self._key = key
        self.max_size = max_size
        self.guard = ReplayGuard()
        self._sessions: dict[tuple[str, bytes], ChaCha20Poly1305] = {}

    def open(self, frame: bytes) -> Envelope:
        """Return the envelope in a sealed frame, or raise WireError saying why it is refused."""
        if len(frame) > self.max_size:
            raise PayloadTooLarge(f"frame of {len(frame)} bytes is over the limit")
        if frame[:2] != SIGNED or len(frame) < 4 + TAG_SIZE:
            raise WireError("not a sealed mover frame")
        n = int.from_bytes(frame[2:4], "big")
        header, sealed = frame[4 : 4 + n], frame[4 + n :]
        fields = unpack(header, max_size=self.max_size)
        if not isinstance(fields, list) or len(fields) != 8:
            raise WireError("envelope header is not an 8-field array")
        version, team, sender, recipient, kind, call_id, timestamp, nonce = fields
        if version != VERSION:
            raise WireError(f"unsupported envelope version {version!r}")
        if team != self.team:
            raise WireError(f"envelope for team {team!r}")
        if not (
            isinstance(sender, str)
            and isinstance(recipient, str)
            and isinstance(kind, str)
            and type(call_id) is int
            and isinstance(timestamp, (int, float))
            and isinstance(nonce, bytes)
            and len(nonce) == 16
            and len(sender) <= 256
        ):
            raise WireError("envelope fields have wrong types")
        try:
            plain = self._aead(sender, nonce[:8]).decrypt(b"\0\0\0\0" + nonce[8:], sealed, header)
        except InvalidTag:
            raise WireError("bad signature (no key, or another team's key)") from None
        payload = unpack(plain, max_size=self.max_size)
        env = Envelope(
            team, sender, kind, call_id, float(timestamp), nonce, payload, recipient=recipient
        )
        why = self.guard.check(env)
        if why is not None:
            raise EnvelopeRefused(f"refused envelope from {sender!r}: {why}", env)
        return env

    def _aead(self, sender: str, epoch: bytes) -> ChaCha20Poly1305:
        aead = self._sessions.pop((sender, epoch), None)  # re-inserted last: LRU order
        if aead is None:
            aead = session_key(self._key, sender, epoch)
        self._sessions[(sender, epoch)] = aead
        if len(self._sessions) > MAX_SESSIONS:
            del self._sessions[next(iter(self._sessions))]
        return aead


def refusal(reason: str) -> bytes:
    """An unsigned refusal frame for a caller that could not be authenticated."""
    return REFUSAL + reason.encode("utf-8", "replace")[:200]


def read_refusal(frame: bytes) -> str | None:
    """The reason in a refusal frame, or None if the frame is not one."""
    if frame[:2] == REFUSAL:
        return frame[2:].decode("utf-8", "replace")
    return None
