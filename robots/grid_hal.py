"""The hardware interface of a robot on a discrete grid (the grid-based papers' robots).

A grid robot stands on one cell. Each round it perceives the cell under it and its 4 (or 8)
neighbours (free, obstacle or occupied by another robot; floor value and colour, resource
amount, base, pheromone), the cells seen along its view rays (the star sensor of the maze
papers), and then acts once: writes its cell, picks or drops resource units, moves one cell or
stays. ``await clock.tick()`` hands the round's action in and returns once the world has
advanced one round. As in ``robots.hal``, the protocols belong to the code that uses them;
``sim_hw.grid._hardware`` implements them over a grid world process.

Conventions:

* Directions are 0 north, 1 east, 2 south, 3 west (then 4 north-east, 5 south-east,
  6 south-west, 7 north-west for the diagonals); north is row - 1.
* Views are relative: a neighbour is a direction, a ray sample a (d_row, d_col) offset. The
  robot never gets its global cell, except through the radio locator (the centre of its cell
  as ``(x, y, 0)`` in cell units), which only mover's range-limited broadcast reads.
* Odometry counts the cells actually moved since the robot was placed (no noise on a grid).
"""

from __future__ import annotations

from contextlib import AbstractAsyncContextManager
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from mover import IdleClock

__all__ = [
    "FREE",
    "OBSTACLE",
    "OCCUPIED",
    "OFFSETS",
    "STAR_RAYS",
    "GridDrive",
    "GridFloor",
    "GridGripper",
    "GridHardware",
    "GridOdometry",
    "GridRadio",
    "GridSenses",
    "Here",
    "Near",
    "RoundClock",
    "Seen",
    "direction_of",
]

#: States of a neighbouring cell.
FREE, OBSTACLE, OCCUPIED = 0, 1, 2

#: (d_row, d_col) of each direction: N, E, S, W, then NE, SE, SW, NW.
OFFSETS: tuple[tuple[int, int], ...] = (
    (-1, 0),
    (0, 1),
    (1, 0),
    (0, -1),
    (-1, 1),
    (1, 1),
    (1, -1),
    (-1, -1),
)

#: The 8 rays of the star view (Linardakis et al., section III-A): 4 straight, then 4 diagonal.
STAR_RAYS: tuple[tuple[int, int], ...] = (
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (-1, 1),
    (1, -1),
    (1, 1),
)


def direction_of(d_row: int, d_col: int) -> int | None:
    """The direction of a one-cell step ``(d_row, d_col)``; None for ``(0, 0)``."""
    if (d_row, d_col) == (0, 0):
        return None
    return OFFSETS.index((d_row, d_col))


@dataclass(frozen=True, slots=True)
class Here:
    """The cell under the robot."""

    value: int  # the floor value (-1: never written)
    colour: int  # the floor colour (0: none)
    resource: int  # resource units lying here
    base: bool  # whether this is the base (nest) cell
    pheromone: float = 0.0


@dataclass(frozen=True, slots=True)
class Near:
    """One neighbouring cell. Floor fields are 0 / False for an obstacle."""

    direction: int
    state: int  # FREE, OBSTACLE or OCCUPIED (another robot stands there)
    value: int
    colour: int
    resource: int
    base: bool
    pheromone: float = 0.0


@dataclass(frozen=True, slots=True)
class Seen:
    """One cell seen along a view ray, relative to the robot (the robot's own cell included)."""

    d_row: int
    d_col: int
    obstacle: bool


@runtime_checkable
class RoundClock(IdleClock, Protocol):
    """Rounds of a lock-step grid world: one action per robot per round.

    A :class:`mover.IdleClock` whose times are rounds: ``hold(t)`` and ``passed(t)`` take a
    round, and an idle robot stays where it is.
    """

    def now(self) -> int:
        """The round the current perception belongs to."""
        ...

    def ended(self) -> bool:
        """Whether the world's observer (the experiment harness, not a sensor) ended the run."""
        ...

    async def tick(self) -> None:
        """Hand in this round's action; return with the next round's perception."""
        ...

    def owned(self, at: int) -> AbstractAsyncContextManager[None]:
        """Let the calling task (and the tasks it starts) drive the rounds from round ``at``.

        Until round ``at`` the clock hands in empty actions (stays) itself, and other tasks'
        ticks stop at round ``at``; inside the block rounds advance only when the owner ticks.
        Members that agree on ``at`` start on the same world round. Raises RuntimeError if
        round ``at`` has already passed.
        """
        ...


@runtime_checkable
class GridSenses(Protocol):
    """What the robot perceives this round."""

    def here(self) -> Here:
        """The cell under the robot."""
        ...

    def around(self) -> tuple[Near, ...]:
        """The 4 (or 8, by the robot's spec) neighbouring cells, in direction order."""
        ...

    def rays(self) -> tuple[Seen, ...]:
        """Cells seen along the view rays (empty when the robot has no view sensor)."""
        ...

    def compass(self) -> tuple[float, float]:
        """Unit (d_row, d_col) toward the base ((0, 0) on it): the ants' nest compass."""
        ...


@runtime_checkable
class GridFloor(Protocol):
    """The writable floor cell under the robot (an RFID floor) and its pheromone."""

    def read(self) -> tuple[int, int]:
        """(value, colour) of the cell under the robot; a pending write shows at once."""
        ...

    def write(self, value: int | None = None, colour: int | None = None) -> None:
        """Write the cell under the robot at this round's end (None: leave as is)."""
        ...

    def scent(self, amount: float) -> None:
        """Add pheromone to the cell under the robot at this round's end."""
        ...


@runtime_checkable
class GridGripper(Protocol):
    """Picking and dropping resource units."""

    def carried(self) -> int:
        """Units carried now."""
        ...

    def pick(self, units: int) -> None:
        """Pick up to ``units`` from the cell under the robot at this round's end."""
        ...

    def drop(self) -> None:
        """Drop the load at this round's end (delivered if the robot is on the base)."""
        ...


@runtime_checkable
class GridDrive(Protocol):
    """One-cell moves."""

    def move(self, direction: int | None) -> None:
        """Move one cell in ``direction`` at this round's end (None: stay)."""
        ...

    def stop(self) -> None:
        """Stay this round."""
        ...

    def moved(self) -> bool:
        """Whether the last round's move happened (blocked by an obstacle or a robot: not)."""
        ...


@runtime_checkable
class GridOdometry(Protocol):
    """Dead reckoning on the grid: cells moved since the robot was placed."""

    def pose(self) -> tuple[float, float, float]:
        """(d_row, d_col, 0.0) from the start cell."""
        ...


@runtime_checkable
class GridRadio(Protocol):
    """The radio: a locator for mover's range-limited broadcast, and the medium's reach.

    ``position`` is ground truth for the transport only. ``in_range`` is what the radio medium
    says of this round: the members whose broadcasts of this round reach this robot. A robot
    uses it to know whose broadcast to wait for, so that a round is reproducible.
    """

    range: float  # cells

    def position(self) -> tuple[float, float, float] | None:
        """The centre of the robot's cell as (x, y, 0) in cell units (x: column, y: row)."""
        ...

    def in_range(self) -> frozenset[str]:
        """Members (not this robot) within radio range of it this round."""
        ...


@dataclass(frozen=True, slots=True)
class GridHardware:
    """Everything a grid robot can touch.

    It has no sonar, bumper, camera, LED or push test: code that serves both kinds of robot
    takes what they share (``clock``, ``drive``, ``odometry``, ``radio``) or is told which
    hardware it has (``robots.backend``: each backend names the procedures its hardware offers).
    """

    id: str
    clock: RoundClock
    drive: GridDrive
    odometry: GridOdometry
    senses: GridSenses
    floor: GridFloor
    gripper: GridGripper
    radio: GridRadio | None = None
