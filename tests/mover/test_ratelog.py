"""The rate-limited log: one line per cause per interval, with a count (no loop, no sleeps)."""

from __future__ import annotations

import logging
from collections.abc import Callable

import pytest

from mover._ratelog import MAX_CAUSES, RateLog


class Timers:
    """A hand-driven clock and timer queue."""

    def __init__(self) -> None:
        self.now = 0.0
        self.due: list[tuple[float, Callable[[], None]]] = []

    def schedule(self, delay: float, callback: Callable[[], None]) -> None:
        self.due.append((self.now + delay, callback))

    def advance(self, seconds: float) -> None:
        self.now += seconds
        ready = [c for t, c in self.due if t <= self.now]
        self.due = [(t, c) for t, c in self.due if t > self.now]
        for callback in ready:
            callback()


@pytest.fixture
def timers() -> Timers:
    return Timers()


def _rates(timers: Timers) -> RateLog:
    return RateLog(
        "r1",
        logging.getLogger("test.ratelog"),
        interval=10.0,
        clock=lambda: timers.now,
        schedule=timers.schedule,
    )


def test_a_flood_of_one_cause_is_one_line_then_one_count_per_interval(
    timers: Timers, caplog: pytest.LogCaptureFixture
) -> None:
    faults = _rates(timers)
    with caplog.at_level(logging.WARNING, "test.ratelog"):
        for i in range(2000):
            faults.warn("tokens", f"'fake-{i}' is no member")
        assert [r.getMessage() for r in caplog.records] == ["r1: 'fake-0' is no member"]
        timers.advance(10.0)
        assert caplog.records[-1].getMessage() == (
            "r1: 'fake-1999' is no member (and 1999 more like it in the last 10 s)"
        )
        faults.warn("tokens", "'late' is no member")  # counted in the next interval
        timers.advance(10.0)
        assert len(caplog.records) == 3 and "(and 1 more like it" in caplog.records[-1].getMessage()
        timers.advance(10.0)  # a quiet interval: the cause is forgotten
        faults.warn("tokens", "'again' is no member")
        assert caplog.records[-1].getMessage() == "r1: 'again' is no member"
    assert faults.counts == {"tokens": 2002}


def test_causes_are_apart_and_bounded(timers: Timers, caplog: pytest.LogCaptureFixture) -> None:
    faults = _rates(timers)
    with caplog.at_level(logging.WARNING, "test.ratelog"):
        faults.warn("hello", "junk hello")
        faults.warn("tokens", "fake token")
        assert len(caplog.records) == 2
        for i in range(10 * MAX_CAUSES):
            faults.warn(f"cause-{i}", "x")
        assert len(caplog.records) == MAX_CAUSES + 1  # the rest share one cause
