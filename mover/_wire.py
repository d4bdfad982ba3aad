"""The wire format: msgpack envelopes, numpy arrays, authenticated encryption, replay refusal.

A team frame is ``b"M2" + u16 header length (big-endian) + header + ciphertext``:

* ``header`` is the msgpack array ``[version, team, sender, recipient, to_epoch, kind,
  call_id, timestamp, nonce]``, sent in the clear and authenticated;
* ``ciphertext`` is the msgpack payload sealed with AES-256-GCM (16-byte tag), the header
  as associated data, under a key derived for the sender's session:
  ``HKDF-SHA256(team key, salt=epoch, info=b"mover/2/" + sender)``;
* ``nonce`` is 16 bytes: the sender's random 8-byte ``epoch`` (new each time a node opens) and a
  big-endian 8-byte counter; the AEAD nonce is four zero bytes and the counter, unique under a
  session's key. (AES-GCM rather than ChaCha20-Poly1305: with AES-NI it seals a MiB 3-5x
  faster on these machines, 0.12 against 0.59 ms.)

``recipient`` and ``to_epoch`` bind a call, a reply or a cancel to the one member it is for and
to that member's session (both empty for broadcasts and hellos, whose topic or challenge is in
the sealed payload), so that an envelope overheard on its way to one member is refused by any
other, and by the same member once it has restarted. ``timestamp`` is the sender's Unix time,
for information only: freshness never depends on wall clocks (see :class:`Sessions`). An
outsider without the key sees the header (who sends what kind of message to whom, and when),
the sizes and the timing — never a payload. A refusal, sent to a caller that could not be
authenticated, is the unsigned frame ``b"MR" + reason`` (UTF-8): a caller never believes one
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
import sys
import time
from dataclasses import dataclass
from typing import Any

import msgpack
from cryptography.exceptions import InvalidTag
from cryptography.hazmat.primitives import hashes
from cryptography.hazmat.primitives.ciphers.aead import AESGCM
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
    np = sys.modules.get("numpy")  # imported only by who has arrays to send (a lean process)
    if np is not None and isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _NUMERIC_KINDS:
            raise WireError(f"cannot send a numpy array of dtype {obj.dtype}")
        dtype = obj.dtype.str.encode("ascii")
        head = struct.pack(f"<B{len(dtype)}sB{obj.ndim}Q", len(dtype), dtype, obj.ndim, *obj.shape)
        return msgpack.ExtType(NDARRAY_EXT, head + np.ascontiguousarray(obj).tobytes())
    if np is not None and isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    raise WireError(f"cannot send a value of type {type(obj).__name__}")


def _ext_hook(code: int, data: bytes) -> Any:
    if code != NDARRAY_EXT:
        raise WireError(f"unknown extension type {code}")
    import numpy as np  # an array came: numpy is needed now (not before: see _default)

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


def unpack(data: bytes | memoryview, *, max_size: int = DEFAULT_MAX_SIZE) -> Any:
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
    to_epoch: bytes = b""
    version: int = VERSION

    @property
    def epoch(self) -> bytes:
        """The sender's session (its node's random epoch)."""
        return self.nonce[:8]

    @property
    def counter(self) -> int:
        """The sender's envelope counter in its session."""
        return int.from_bytes(self.nonce[8:], "big")


class EnvelopeRefused(WireError):
    """An authentic envelope refused all the same (replayed, for someone else). Anyone who
    overheard it can send it again, so a refusal of it is never sealed (a sealed refusal the
    sender believes would let an outsider end the sender's call); only :class:`SessionChanged`
    is answered sealed."""

    def __init__(self, message: str, envelope: Envelope) -> None:
        super().__init__(message)
        self.envelope = envelope


class SessionChanged(EnvelopeRefused):
    """An envelope for an earlier session of its recipient (which has restarted since)."""


class SessionUnknown(EnvelopeRefused):
    """A broadcast from a session this node has not verified yet (see :class:`Sessions`)."""


def session_key(team_key: bytes, sender: str, epoch: bytes) -> AESGCM:
    """The AEAD of one sender's session (see the module docstring)."""
    info = b"mover/2/" + sender.encode()
    hkdf = HKDF(algorithm=hashes.SHA256(), length=32, salt=epoch, info=info)
    return AESGCM(hkdf.derive(team_key))


class Sealer:
    """Seals outgoing envelopes for one sender under a team key."""

    def __init__(self, team: str, sender: str, key: bytes, *, max_size: int = DEFAULT_MAX_SIZE):
        self.team = team
        self.sender = sender
        self.epoch = os.urandom(8)
        self._aead = session_key(key, sender, self.epoch)
        self._counter = 0
        self.max_size = max_size
        # One packer kept: a payload is packed into its buffer (reused, at most as large as the
        # largest payload sealed) and encrypted from there, with no copy out of msgpack and no
        # fresh large allocation (which costs page faults: see docs/transport.md).
        self._packer = msgpack.Packer(default=_default, use_bin_type=True, autoreset=False)

    def seal(
        self, kind: str, payload: Any, call_id: int = 0, *, to: str = "", to_epoch: bytes = b""
    ) -> bytearray:
        """Return the sealed frame of a new envelope for ``to`` in its session ``to_epoch``
        (empty: the team, or whoever asked); raise PayloadTooLarge over the limit."""
        packer = self._packer
        try:
            packer.pack(payload)
            with packer.getbuffer() as packed:
                return self.seal_packed(kind, packed, call_id, to=to, to_epoch=to_epoch)
        except (TypeError, ValueError, OverflowError) as exc:
            raise WireError(f"cannot encode value: {exc}") from exc
        finally:
            packer.reset()

    def seal_packed(
        self,
        kind: str,
        payload: bytes | memoryview,
        call_id: int = 0,
        *,
        to: str = "",
        to_epoch: bytes = b"",
    ) -> bytearray:
        """Like :meth:`seal` for a payload already encoded with :func:`pack`."""
        self._counter += 1
        counter = self._counter.to_bytes(8, "big")
        nonce = self.epoch + counter
        header = pack(
            [VERSION, self.team, self.sender, to, to_epoch, kind, call_id, time.time(), nonce]
        )
        size = 4 + len(header) + len(payload) + TAG_SIZE
        if size > self.max_size:
            raise PayloadTooLarge(
                f"{kind} envelope of {size} bytes is over the limit of {self.max_size}"
            )
        # one buffer, sealed in place: a large payload is copied once, by the cipher
        prefix = SIGNED + len(header).to_bytes(2, "big") + header
        frame = bytearray(len(prefix) + len(payload) + TAG_SIZE)
        frame[: len(prefix)] = prefix
        self._aead.encrypt_into(
            b"\0\0\0\0" + counter, payload, header, memoryview(frame)[len(prefix) :]
        )
        return frame


class Sessions:
    """Which envelopes are fresh, without trusting anyone's wall clock, in bounded memory.

    * An envelope addressed to this node (a call, a reply, a cancel) names this node's session
      (``to_epoch``), so it was made during this node's lifetime: a replay to another member,
      or to this member after a restart, is refused. Within the session, each sender session
      keeps the highest counter seen and a bitmap of the last ``window`` counters (as IPsec
      does), so envelopes a little out of order across zenoh's threads pass once.
    * A broadcast counts only from a sender session this node has verified with a challenge
      (the signed hello membership performs, :meth:`learn`), and only if it was sent after that
      hello (its counter is above the one the hello carried): a broadcast overheard before a
      member joined, or before a sender restarted, is refused.
    * At most ``sessions`` sender sessions are remembered (the least recently heard go first);
      a counter that jumps ahead by more than the window clears the bitmap instead of growing.
    """

    def __init__(self, *, window: int = 4096, sessions: int = MAX_SESSIONS) -> None:
        self.window = window
        self.sessions = sessions
        self._mask = (1 << window) - 1
        self._state: dict[bytes, list[int]] = {}  # epoch -> [highest, bitmap]
        self._verified: dict[str, tuple[bytes, int]] = {}  # sender -> (epoch, counter at hello)

    def learn(self, sender: str, epoch: bytes, counter: int) -> None:
        """``sender``'s current session, verified by a fresh challenge at ``counter``."""
        known = self._verified.get(sender)
        if known is not None and known[0] == epoch:  # the same session met again (a link
            counter = known[1]  # came back): what it sent since we first met still counts
        self._verified[sender] = (epoch, counter)
        self._verified[sender] = self._verified.pop(sender)  # most recent last
        while len(self._verified) > self.sessions:
            del self._verified[next(iter(self._verified))]

    def verified(self, sender: str) -> bytes | None:
        """``sender``'s verified session, if any."""
        known = self._verified.get(sender)
        return None if known is None else known[0]

    def admit(self, env: Envelope, me: str, my_epoch: bytes) -> None:
        """Record a fresh envelope, or raise :class:`EnvelopeRefused` saying why not."""
        if env.kind == "hello":  # answers our own fresh challenge: checked by the asker
            return
        known = self._verified.get(env.sender)
        if env.recipient or env.to_epoch:
            if env.recipient != me:
                raise EnvelopeRefused(f"an envelope for {env.recipient!r}, not for {me!r}", env)
            if env.to_epoch != my_epoch:
                raise SessionChanged(f"an envelope for an earlier session of {me!r}", env)
            # Made during this session of ours: the window of the sender's session (whichever
            # it is: a sender that just restarted may call before we verified it) suffices.
        elif known is None or known[0] != env.epoch:
            raise SessionUnknown(f"a broadcast from an unverified session of {env.sender!r}", env)
        elif env.counter <= known[1]:
            raise EnvelopeRefused(f"a broadcast of {env.sender!r} from before we met", env)
        why = self._window(env.epoch, env.counter)
        if why is not None:
            raise EnvelopeRefused(f"refused envelope from {env.sender!r}: {why}", env)

    def _window(self, epoch: bytes, counter: int) -> str | None:
        state = self._state.pop(epoch, None)  # re-inserted last: the dict is in LRU order
        why = None
        if state is None:
            state = [counter, 1]
        else:
            highest, bitmap = state
            if counter > highest:
                shift = counter - highest
                state[1] = ((bitmap << shift) | 1) & self._mask if shift < self.window else 1
                state[0] = counter
            elif highest - counter >= self.window:
                why = "replayed (too old for the window)"
            elif bitmap >> (highest - counter) & 1:
                why = "replayed nonce"
            else:
                state[1] = bitmap | 1 << (highest - counter)
        self._state[epoch] = state
        while len(self._state) > self.sessions:
            del self._state[next(iter(self._state))]
        return why


class Opener:
    """Verifies, decrypts and decodes incoming frames for one team."""

    def __init__(self, team: str, key: bytes, *, max_size: int = DEFAULT_MAX_SIZE) -> None:
        self.team = team
        self._key = key
        self.max_size = max_size
        self._keys: dict[tuple[str, bytes], AESGCM] = {}
        # Plaintexts are decrypted into this buffer (kept, as large as the largest frame
        # opened, at most max_size) and decoded from there: decoding copies out what it keeps.
        self._plain = bytearray()

    def open(self, frame: bytes) -> Envelope:
        """Return the envelope in a sealed frame (authentic, not yet judged fresh: see
        :class:`Sessions`), or raise WireError saying why it is refused."""
        if len(frame) > self.max_size:
            raise PayloadTooLarge(f"frame of {len(frame)} bytes is over the limit")
        if frame[:2] != SIGNED or len(frame) < 4 + TAG_SIZE:
            raise WireError("not a sealed mover frame")
        n = int.from_bytes(frame[2:4], "big")
        header, sealed = frame[4 : 4 + n], memoryview(frame)[4 + n :]  # no copy of the body
        fields = unpack(header, max_size=self.max_size)
        if not isinstance(fields, list) or len(fields) != 9:
            raise WireError("envelope header is not a 9-field array")
        version, team, sender, recipient, to_epoch, kind, call_id, timestamp, nonce = fields
        if version != VERSION:
            raise WireError(f"unsupported envelope version {version!r}")
        if team != self.team:
            raise WireError(f"envelope for team {team!r}")
        if not (
            isinstance(sender, str)
            and isinstance(recipient, str)
            and isinstance(to_epoch, bytes)
            and isinstance(kind, str)
            and type(call_id) is int
            and isinstance(timestamp, (int, float))
            and isinstance(nonce, bytes)
            and len(nonce) == 16
            and len(sender) <= 256
        ):
            raise WireError("envelope fields have wrong types")
        size = len(sealed) - TAG_SIZE
        if size < 0:
            raise WireError("truncated frame")
        if len(self._plain) < size:
            self._plain = bytearray(size)
        with memoryview(self._plain)[:size] as plain:
            try:
                aead = self._aead(sender, nonce[:8])
                aead.decrypt_into(b"\0\0\0\0" + nonce[8:], sealed, header, plain)
            except InvalidTag:
                raise WireError("bad signature (no key, or another team's key)") from None
            payload = unpack(plain, max_size=self.max_size)
        return Envelope(
            team,
            sender,
            kind,
            call_id,
            float(timestamp),
            nonce,
            payload,
            recipient=recipient,
            to_epoch=to_epoch,
        )

    def _aead(self, sender: str, epoch: bytes) -> AESGCM:
        aead = self._keys.pop((sender, epoch), None)  # re-inserted last: LRU order
        if aead is None:
            aead = session_key(self._key, sender, epoch)
        self._keys[(sender, epoch)] = aead
        if len(self._keys) > MAX_SESSIONS:
            del self._keys[next(iter(self._keys))]
        return aead


def _array_header(n: int) -> bytes:
    """The msgpack header of an array of ``n`` elements."""
    if n < 16:
        return bytes([0x90 | n])
    if n < 65536:
        return b"\xdc" + n.to_bytes(2, "big")
    return b"\xdd" + n.to_bytes(4, "big")


def broadcast_frames(sealer: Sealer, topic: str, items: list[bytes]) -> list[bytearray]:
    """Sealed ``bc`` frames carrying ``items`` (each a :func:`pack`-ed ``[data, where, range]``)
    on ``topic``: as few as fit under half the size limit, each payload ``[topic, [item, ...]]``
    (a burst costs one seal and one zenoh message). An item alone over the limit raises
    PayloadTooLarge."""
    limit = sealer.max_size // 2
    head = pack(topic)
    frames = []
    start = 0
    while start < len(items):
        end, size = start, 0
        while end < len(items) and (end == start or size + len(items[end]) < limit):
            size += len(items[end])
            end += 1
        payload = b"\x92" + head + _array_header(end - start) + b"".join(items[start:end])
        frames.append(sealer.seal_packed("bc", payload))
        start = end
    return frames


def read_broadcast(env: Envelope) -> tuple[str, list[Any]]:
    """The topic and items of a ``bc`` envelope; raise WireError if it is not one."""
    payload = env.payload
    if env.kind != "bc" or not isinstance(payload, list) or len(payload) != 2:
        raise WireError("not a broadcast envelope")
    topic, items = payload
    if not isinstance(topic, str) or not isinstance(items, list):
        raise WireError("not a broadcast envelope")
    return topic, items


def refusal(reason: str) -> bytes:
    """An unsigned refusal frame for a caller that could not be authenticated."""
    return REFUSAL + reason.encode("utf-8", "replace")[:200]


def read_refusal(frame: bytes) -> str | None:
    """The reason in a refusal frame, or None if the frame is not one."""
    if frame[:2] == REFUSAL:
        return frame[2:].decode("utf-8", "replace")
    return None
