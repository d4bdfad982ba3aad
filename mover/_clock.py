"""The one clock protocol that a run, a robot's hardware and a world link share.

A collective in simulated time needs four things of the hardware it runs on: what time it is,
to wait until the robot has gone on past a time, to hold the robot at a time, and to idle it.
The HAL clocks (``robots.hal.Clock``, ``robots.grid_hal.RoundClock``) extend this protocol with
their devices' own methods; a run's clock (``ProgramHost.clock``) implements it. Its words are
written once, here.
"""

from __future__ import annotations

from contextlib import AbstractAsyncContextManager
from typing import Protocol, runtime_checkable

__all__ = ["IdleClock"]


@runtime_checkable
class IdleClock(Protocol):
    """Simulated (or hardware) time a collective can wait on, hold and idle.

    Times are those of the hardware's readings: seconds on a continuous world, rounds on a grid.
    """

    def now(self) -> float:
        """The time of the last readings."""
        ...

    async def passed(self, t: float) -> None:
        """Return once this robot has gone on past time ``t``: handed in a command on readings
        of time ``t`` or later (at once if it has); raise ``HardwareLost`` if the hardware goes
        away meanwhile. A robot whose program stopped at ``t`` hands in nothing there."""
        ...

    def hold(self, t: float | None) -> None:
        """Hand in no command on readings later than ``t`` until ``hold(None)``: a tick waits
        meanwhile (a ``distributed_or`` holds a member that went past the earliest finish until
        the step is decided, so that it stops on the same tick whatever the wall clock does)."""
        ...

    def reach(self, t: float) -> float:
        """Where a robot is sure to get past ``t`` whatever the wall clock does, for a hold:
        ``t`` itself, or with a control delay of K ticks (a lock-step world that runs up to K
        ticks ahead of the commands) a time between the ticks K - 1 and K after ``t``'s: a
        ``distributed_or``'s losers go on to there and hold, however far the world let each
        run before it was asked (docs/reproducible-runs.md)."""
        ...

    def idling(self) -> AbstractAsyncContextManager[None]:
        """Be idle for the block: the drive is stopped, and a lock-step world neither waits
        for this robot's commands nor advances a tick for it. Entering and leaving are
        acknowledged by the world: once the block is left, the world waits for this robot's
        command again, from the tick of the readings then. No ticks inside the block."""
        ...
