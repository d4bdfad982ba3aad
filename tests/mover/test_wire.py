"""Unit tests of the wire format, authentication and replay refusal (no network)."""

from __future__ import annotations

import numpy as np
import pytest

from mover import PayloadTooLarge, WireError, pack, unpack
from mover._wire import (
    Envelope,
    EnvelopeRefused,
    Opener,
    Sealer,
    SessionChanged,
    Sessions,
    SessionUnknown,
)

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
    frame = Sealer("alpha", "ernst", KEY).seal("call", ["add", [1, 2], {}], 7, to="hugo")
    env = Opener("alpha", KEY).open(bytes(frame))
    assert (env.sender, env.kind, env.call_id, env.recipient) == ("ernst", "call", 7, "hugo")
    assert env.payload == ["add", [1, 2], {}]


def test_payloads_are_encrypted() -> None:
    frame = Sealer("alpha", "ernst", KEY).seal("bc", ["news", [["the-secret-4711", None, None]]])
    assert b"the-secret-4711" not in frame and b"news" not in frame
    assert b"ernst" in frame  # the header is authenticated, not hidden


def test_wrong_key_or_team_is_refused() -> None:
    frame = Sealer("alpha", "ernst", KEY).seal("call", None)
    with pytest.raises(WireError, match="bad signature"):
        Opener("alpha", b"x" * 32).open(bytes(frame))
    with pytest.raises(WireError, match="team 'alpha'"):
        Opener("beta", KEY).open(bytes(frame))
    tampered = frame[:-20] + bytes([frame[-20] ^ 1]) + frame[-19:]
    with pytest.raises(WireError, match="bad signature"):
        Opener("alpha", KEY).open(bytes(tampered))
    header_changed = frame.replace(b"ernst", b"ernsT")  # the header is authenticated too
    with pytest.raises(WireError, match="bad signature"):
        Opener("alpha", KEY).open(bytes(header_changed))


def _addressed(n: int) -> tuple[Sealer, Opener, Sessions, list[Envelope]]:
    sealer, opener, sessions = Sealer("alpha", "ernst", KEY), Opener("alpha", KEY), Sessions()
    frames = [sealer.seal("call", i, i, to="hugo", to_epoch=b"H" * 8) for i in range(n)]
    return sealer, opener, sessions, [opener.open(bytes(f)) for f in frames]


def test_replay_is_refused_and_out_of_order_accepted() -> None:
    _, _, sessions, envs = _addressed(5)
    for e in (envs[1], envs[0], envs[4], envs[2]):
        sessions.admit(e, "hugo", b"H" * 8)
    with pytest.raises(EnvelopeRefused, match="replayed"):
        sessions.admit(envs[0], "hugo", b"H" * 8)
    sessions.admit(envs[3], "hugo", b"H" * 8)
    with pytest.raises(EnvelopeRefused, match="replayed"):
        sessions.admit(envs[3], "hugo", b"H" * 8)


def test_an_envelope_for_someone_else_or_an_earlier_session_is_refused() -> None:
    _, _, sessions, envs = _addressed(1)
    with pytest.raises(EnvelopeRefused, match="for 'hugo', not for 'elvis'"):
        sessions.admit(envs[0], "elvis", b"H" * 8)
    with pytest.raises(SessionChanged, match="earlier session of 'hugo'"):
        sessions.admit(envs[0], "hugo", b"N" * 8)  # hugo restarted since


def test_broadcasts_count_only_from_a_verified_session_and_after_we_met() -> None:
    sealer, opener = Sealer("alpha", "ernst", KEY), Opener("alpha", KEY)
    early = opener.open(bytes(sealer.seal("bc", "overheard before we met")))
    sessions = Sessions()
    with pytest.raises(SessionUnknown):
        sessions.admit(early, "hugo", b"H" * 8)
    hello = opener.open(bytes(sealer.seal("hello", {"challenge": b"c"})))
    sessions.admit(hello, "hugo", b"H" * 8)  # a hello answers our challenge: always let in
    sessions.learn("ernst", hello.epoch, hello.counter)
    with pytest.raises(EnvelopeRefused, match="before we met"):
        sessions.admit(early, "hugo", b"H" * 8)  # a replay to a late joiner
    fresh = opener.open(bytes(sealer.seal("bc", "after")))
    sessions.admit(fresh, "hugo", b"H" * 8)
    with pytest.raises(EnvelopeRefused, match="replayed"):
        sessions.admit(fresh, "hugo", b"H" * 8)
    restarted = Sealer("alpha", "ernst", KEY)  # same name, new session
    with pytest.raises(SessionUnknown):
        sessions.admit(opener.open(bytes(restarted.seal("bc", "x"))), "hugo", b"H" * 8)


def test_replay_state_is_bounded_whatever_the_counter_does() -> None:
    sessions = Sessions(window=64, sessions=8)
    opener = Opener("alpha", KEY)
    sealer = Sealer("alpha", "ernst", KEY)
    sealer._counter = 2**62  # a counter that jumps far ahead
    env = opener.open(bytes(sealer.seal("call", 0, 0, to="hugo", to_epoch=b"H" * 8)))
    sessions.admit(env, "hugo", b"H" * 8)
    assert all(state[1].bit_length() <= 64 for state in sessions._state.values())
    for _ in range(20):  # more sessions than it keeps
        s2 = Sealer("alpha", "ernst", KEY)
        sessions.admit(
            opener.open(bytes(s2.seal("call", 0, 0, to="hugo", to_epoch=b"H" * 8))),
            "hugo",
            b"H" * 8,
        )
    assert len(sessions._state) <= 8


def test_size_limit() -> None:
    sealer = Sealer("alpha", "ernst", KEY, max_size=1024)
    with pytest.raises(PayloadTooLarge):
        sealer.seal("call", b"x" * 2000)
    big = Sealer("alpha", "ernst", KEY).seal("call", b"x" * 2000)
    with pytest.raises(PayloadTooLarge):
        Opener("alpha", KEY, max_size=1024).open(bytes(big))
