"""The answers a callee keeps for copies of its calls (``mover._rpc._Answers``): a copy of a
call admitted lately is answered with the same sealed bytes, at once or when the call ends, in
bounded count, bytes and age (issue 24: an outsider's copy that comes first)."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from mover import _rpc
from mover._rpc import ANSWERS_COUNT, WAITING, _Answers


def _nonce(i: int) -> bytes:
    return b"epoch..." + i.to_bytes(8, "big")


def _query(name: str) -> Any:
    """A stand-in for a zenoh query (the answers only hold it and hand it back)."""
    return name


class _Replies:
    def __init__(self) -> None:
        self.sent: list[tuple[Any, bytes | bytearray]] = []

    def __call__(self, query: Any, frame: bytes | bytearray) -> None:
        self.sent.append((query, frame))


async def test_a_copy_of_an_answered_call_gets_the_same_bytes_and_an_unknown_one_nothing() -> None:
    answers, replies = _Answers(), _Replies()
    assert answers.keep(_nonce(1), bytearray(b"M2 sealed")) is None  # nobody waited
    assert answers.again(_query("copy"), _nonce(1), replies)
    assert replies.sent == [("copy", bytearray(b"M2 sealed"))]
    assert not answers.again(_query("other"), _nonce(2), replies)
    answers.clear()


async def test_copies_of_a_running_call_wait_for_its_answer_a_few_at_most() -> None:
    answers, replies = _Answers(), _Replies()
    answers.running(_nonce(1))
    copies = [_query(f"copy{i}") for i in range(WAITING + 2)]
    assert [answers.again(q, _nonce(1), replies) for q in copies] == [True] * WAITING + [False] * 2
    assert replies.sent == []  # nothing to send yet
    assert answers.keep(_nonce(1), b"M2 answer") == copies[:WAITING]
    answers.clear()


async def test_answers_kept_are_bounded_in_count_and_bytes() -> None:
    answers, replies = _Answers(), _Replies()
    for i in range(3 * ANSWERS_COUNT):
        answers.keep(_nonce(i), b"M2 small")
    assert len(answers) <= 2 * ANSWERS_COUNT
    assert answers.again(_query("late"), _nonce(3 * ANSWERS_COUNT - 1), replies)
    assert not answers.again(_query("too late"), _nonce(0), replies)
    big = bytes(3 * 1024 * 1024)
    for i in range(4):
        answers.keep(_nonce(10_000 + i), big)
    assert len(answers) == 2  # the last two 3 MiB answers (4 MiB a generation): 6 MiB
    answers.clear()


async def test_answers_are_forgotten_after_their_time(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_rpc, "ANSWERS_KEPT", 0.2)
    answers, replies = _Answers(), _Replies()
    answers.keep(_nonce(1), b"M2 answer")
    await asyncio.sleep(0.05)
    assert answers.again(_query("soon"), _nonce(1), replies)
    await asyncio.sleep(0.3)  # two turns: from half the time to all of it
    assert not answers.again(_query("late"), _nonce(1), replies)
    assert len(answers) == 0
    await asyncio.sleep(0.15)
    assert answers._timer is None  # nothing kept, no timer left running
