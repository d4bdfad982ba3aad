"""What both wings' simulated robots share: the clock calls that only pass through to the
robot's :class:`~sim_hw._ticks.Ticks`.

:class:`sim_hw.continuous.SimHardware` (a tick of simulated seconds) and
:class:`sim_hw.grid._hardware.GridRobot` (a round) each extend :class:`TickedRobot` with their
commands and readings; ``idling``, ``hold``, ``passed`` and ``reach`` (the parts of
``robots.hal.Clock`` and ``robots.grid_hal.RoundClock`` that a team step in simulated time
uses, see ``mover._clock.IdleClock``) are written here once.
"""

from __future__ import annotations

import contextlib

from ._ticks import Ticks
from ._types import Command


class TickedRobot:
    """A simulated robot's clock calls over its :class:`Ticks` (``self._ticks``, set by the
    extension's constructor); the extension gives :meth:`_idle`, the command it stands on
    while idle."""

    _ticks: Ticks

    def _idle(self) -> Command:
        """The command that stands while the robot idles (extended: the drive stopped)."""
        raise NotImplementedError

    def idling(self) -> contextlib.AbstractAsyncContextManager[None]:
        """Be idle for the block: the robot stands on :meth:`_idle`'s command, a lock-step world
        does not wait for it."""
        return self._ticks.idling(self._idle)

    def reach(self, t: float) -> float:
        """How far past ``t`` this robot surely gets: ``t``, or later with a control delay
        (see ``Ticks.reach``)."""
        return self._ticks.reach(t)

    def hold(self, t: float | None) -> None:
        """Hand in nothing on readings later than ``t`` until ``hold(None)`` (see ``Ticks``)."""
        self._ticks.hold(t)

    async def passed(self, t: float) -> None:
        """Return once a command was handed in on readings of time ``t`` or later (a tick's
        simulated seconds, or a round): this robot went on past ``t``."""
        await self._ticks.passed(t)


class ClockView:
    """The clock calls both wings' clock views pass through (extended with the wing's own)."""

    def __init__(self, robot: TickedRobot) -> None:
        self.idling, self.passed = robot.idling, robot.passed
        self.hold, self.reach = robot.hold, robot.reach
