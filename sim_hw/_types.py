"""What the lock-step door and a world agree on: commands, readings, the stepper protocols,
and the error a robot gets once it is out of the world.

Kept apart from the door (``sim_hw._lockstep``) and its schedules (``sim_hw._schedules``) so
that both, the frames and the robot's link import them without importing each other.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any, Protocol, runtime_checkable

from robots.hal import HardwareLost

Command = Mapping[str, Any]
"""A robot's command for a tick, as the world defines it (opaque to the door)."""
Readings = Any
"""A robot's readings after a tick, as the world defines them (opaque to the door)."""


class RobotDropped(HardwareLost, LookupError):
    """The robot is not (or no longer) in the world: it left, or it was dropped for silence."""


class Stepper(Protocol):
    """A world as the door drives it."""

    #: Whether a joining robot is in the world at once, before the first tick (see the door).
    admits_early: bool
    #: What the world calls a command and a tick, for log lines (e.g. "action", "round").
    words: tuple[str, str]

    @property
    def tick(self) -> int:
        """Ticks done."""

    def robots(self) -> Collection[str]:
        """Ids of the robots in the world."""

    def prepare(self, robot: str, spec: Mapping[str, Any] | None) -> Any:
        """Check a join's settings (raise ``ValueError`` to refuse it); returns what
        :meth:`admit` takes."""

    def admit(self, robot: str, prepared: Any) -> None:
        """Place ``robot`` (raise ``ValueError`` if it cannot be placed); ``prepared`` is what
        :meth:`prepare` made of its settings (each stepper's own type, opaque to the door)."""

    def start(self) -> None:
        """The expected robots are in and nothing has moved yet."""

    def advance(self, commands: Mapping[str, Command]) -> None:
        """Advance one tick; ``commands`` holds every robot's command, in id order."""

    def sense(self) -> None:
        """Robots were placed or the world advanced: bring every robot's readings up to date."""

    def readings(self, robot: str) -> Readings:
        """``robot``'s readings as of now."""

    def spec_of(self, robot: str) -> dict[str, Any]:
        """The settings ``robot`` was admitted with (the join's answer)."""

    def remove(self, robot: str) -> None:
        """Take ``robot`` out (no error if it is not there)."""


@runtime_checkable
class TurnStepper(Stepper, Protocol):
    """A stepper whose robots can also act one at a time (sequential turns)."""

    def act(self, robot: str, command: Command) -> None:
        """Apply ``robot``'s command now, in its turn."""

    def end_round(self) -> None:
        """Every robot has acted: close the round (the tick count goes up)."""

    def begin_round(self) -> None:
        """Robots waiting to join were placed: the new round begins."""

    def sense_one(self, robot: str) -> Readings:
        """``robot``'s perception just before its turn."""
