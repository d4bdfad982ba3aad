"""Unit tests of the wire format, authentication and replay refusal (no network)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from mover import PayloadTooLarge, WireError, pack, unpack
from mover._wire import Envelope, Opener, ReplayGuard, Sealer

KEY = b"k" * 32


@pytest.mark.parametrize(
    "value",
    [
        None,
        True,
        3,
        -(2**40),
        1.5,
        "txt",
        b"\x00bytes",
        [1, [2, 3]],
        {"a": {1: "int key"}},
    ],
)
def test_plain_values_round_trip(value: object) -> None:
    assert unpack(pack(value)) == value


@pytest.mark.parametrize("dtype", ["<f8", "<f4", "<i4", "|u1", "|b1", "<c16", ">i2"])
def test_numpy_arrays_round_trip_natively(dtype: str) -> None:
    a = (np.arange(24).reshape(2, 3, 4) % 7).astype(dtype)
    b = unpack(pack({"a": a}))["a"]
    assert isinstance(b, np.ndarray)
    assert b.dtype == a.dtype and b.shape == a.shape
    assert np.array_equal(a, b)
    b[0, 0, 0] = 1  # a writable copy


def test_scalar_and_empty_arrays() -> None:
    assert unpack(pack(np.float32(2.5))) == 2.5
    assert unpack(pack(np.zeros((0, 3)))).shape == (0, 3)


def test_object_arrays_and_unknown_types_are_refused() -> None:
    with pytest.raises(WireError, match="dtype object"):
        pack(np.array([object()]))
    with pytest.raises(WireError, match="type function"):
        pack(lambda: None)


def test_malformed_input_raises_wire_error() -> None:
    for junk in (b"\xc1", b"\x92\x01", b"\xc7\x03\x09abc", b""):
        with pytest.raises(WireError):
            unpack(junk)


def test_seal_and_open() -> None:
    frame = Sealer("alpha", "ernst", KEY).seal("call", ["add", [1, 2], {}], 7)
    env = Opener("alpha", KEY).open(frame)
    assert (env.sender, env.kind, env.call_id) == ("ernst", "call", 7)
    assert env.payload == ["add", [1, 2], {}]


def test_wrong_key_or_team_is_refused() -> None:
    frame = Sealer("alpha", "ernst", KEY).seal("call", None)
    with pytest.raises(WireError, match="bad signature"):
        Opener("alpha", b"x" * 32).open(frame)
    with pytest.raises(WireError, match="team 'alpha'"):
        Opener("beta", KEY).open(frame)
    tampered = frame[:-40] + bytes([frame[-40] ^ 1]) + frame[-39:]
    with pytest.raises(WireError, match="bad signature"):
        Opener("alpha", KEY).open(tampered)


def test_replay_is_refused_and_out_of_order_accepted() -> None:
    sealer, opener = Sealer("alpha", "ernst", KEY), Opener("alpha", KEY)
    frames = [sealer.seal("bc", i) for i in range(5)]
    for f in (frames[1], frames[0], frames[4], frames[2]):
        opener.open(f)
    with pytest.raises(WireError, match="replayed"):
        opener.open(frames[0])
    opener.open(frames[3])
    with pytest.raises(WireError, match="replayed"):
        opener.open(frames[3])


def test_stale_and_too_old_envelopes_are_refused() -> None:
    guard = ReplayGuard(max_age=30, window=8)
    now = time.time()

    def env(counter: int, ts: float = now) -> Envelope:
        return Envelope("alpha", "s", "bc", 0, ts, b"E" * 8 + counter.to_bytes(8, "big"), None)

    assert guard.check(env(1, now - 31), now) == "stale timestamp (+31.0 s)"
    assert guard.check(env(20), now) is None
    assert guard.check(env(5), now) == "replayed (too old for the window)"
    assert guard.check(env(19), now) is None


def test_size_limit() -> None:
    sealer = Sealer("alpha", "ernst", KEY, max_size=1024)
    with pytest.raises(PayloadTooLarge):
        sealer.seal("call", b"x" * 2000)
    big = Sealer("alpha", "ernst", KEY).seal("call", b"x" * 2000)
    with pytest.raises(PayloadTooLarge):
        Opener("alpha", KEY, max_size=1024).open(big)
