"""The hardware backend: how a robot process gets its hardware, and what it exports for it.

A backend is an object installed under the ``mover.hardware`` entry-point group and chosen by
name where the process is launched (``mover robot --hardware grid``). It says which options it
accepts, connects a robot to its hardware, and names the ``robot.*`` procedures the process
exports for that hardware — so the robot process never asks a device whether it is there:
a backend over :class:`~robots.hal.Hardware` offers :func:`~robots.procedures.body_procedures`,
one over :class:`~robots.grid_hal.GridHardware` offers
:func:`~robots.procedures.grid_procedures`.

The process itself only touches what every hardware has (:class:`BaseHardware`): it keeps the
clock idle while no program drives it, stops the drive, and hands the radio's locator to
mover's range-limited broadcast.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol, TypeVar, runtime_checkable

from mover import IdleClock, Node

from .hal import RadioLocator

__all__ = ["BaseHardware", "HardwareBackend", "check_options"]


class _Stops(Protocol):
    def stop(self) -> None: ...


class BaseHardware(Protocol):
    """What the robot process touches on any hardware (continuous or grid).

    ``clock.idling()`` keeps the robot idle while no run drives it, ``clock.now()``,
    ``clock.passed(t)`` and ``clock.hold(t)`` make the host's run clock (a
    :class:`mover.IdleClock`, which both HALs' clocks extend); ``drive.stop()``
    stops the motors; ``radio`` is the transport's ground-truth locator.
    """

    @property
    def clock(self) -> IdleClock:
        """The hardware's clock, idle while no run drives it."""
        ...

    @property
    def drive(self) -> _Stops:
        """The drive, stopped when the robot becomes idle."""
        ...

    @property
    def radio(self) -> RadioLocator | None:
        """Where the radio is, for the range-limited broadcast only (None: unknown)."""
        ...


H = TypeVar("H", bound=BaseHardware)


@runtime_checkable
class HardwareBackend(Protocol[H]):
    """Connects a robot process to hardware of type ``H`` (see the module docstring)."""

    options: frozenset[str]
    """The names of the options :meth:`connect` accepts (``world``, ``call_timeout``...)."""

    async def connect(
        self, node: Node, robot_id: str, spec: Mapping[str, Any], **options: Any
    ) -> H:
        """Join the hardware as ``robot_id`` (the node's name) with body ``spec``; return it.

        ``options`` are among :attr:`options`; the process checks that before calling.
        """
        ...

    def procedures(self, hw: H) -> Mapping[str, Callable[..., Any]]:
        """The ``robot.*`` procedures the robot process exports for ``hw``, by name."""
        ...


def check_options(name: str, backend: HardwareBackend[Any], options: Mapping[str, Any]) -> None:
    """Raise ValueError naming ``backend``'s options if ``options`` has one it does not take."""
    unknown = sorted(set(options) - backend.options)
    if unknown:
        takes = ", ".join(sorted(backend.options)) or "none"
        raise ValueError(
            f"hardware backend {name!r} takes no option {', '.join(map(repr, unknown))} "
            f"(its options: {takes})"
        )
