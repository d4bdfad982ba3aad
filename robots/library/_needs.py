"""What a program needs of a robot's hardware, checked as it starts.

A program declares the devices it cannot do without::

    @needs("camera")
    async def follow_the_red_one(robot: Robot, team: RunTeam) -> ...

and on a robot that lacks one (a camera on a Thymio) it fails as it starts, before it moves
anything, with one line naming the device: ``MissingDevice: program follow_the_red_one needs
a camera; the robot's hardware (ThymioHardware) has none (it has: clock, drive, …)``. The run
reports it at the launcher as it does any expected fault (one line, no traceback). A device is
an attribute of the hardware that is not None (``camera``, ``bumper``, ``sonar``, ``ground``…).
A program that can do without a device (a camera-less fallback) declares nothing and tests
``robot.hw.camera is None`` itself.
"""

from __future__ import annotations

import functools
from collections.abc import Awaitable, Callable
from dataclasses import fields, is_dataclass
from typing import Concatenate, ParamSpec, TypeVar

from robots.hal import HardwareLost

__all__ = ["MissingDevice", "needs", "require"]

P = ParamSpec("P")
R = TypeVar("R")
T = TypeVar("T")


class MissingDevice(HardwareLost):
    """A program needs a device the robot does not have (a camera on a Thymio): said in one
    line as the program starts. A HardwareLost, so that a run reports it as an expected fault;
    unlike a lost robot, waiting will not bring the device."""


def require(hw: object, *devices: str, program: str = "this program") -> None:
    """Raise :class:`MissingDevice` naming the first of ``devices`` that ``hw`` lacks.

    A program calls it as it starts (``require(robot.hw, "ground", "sonar")``), or declares
    the devices with :func:`needs`, so that on hardware without one it fails at once, in one
    line, rather than halfway.
    """
    for name in devices:
        if getattr(hw, name, None) is None:
            if hw is None:
                raise MissingDevice(f"{program} needs a {name}; this member has no hardware")
            has = [
                f.name
                for f in (fields(hw) if is_dataclass(hw) else ())
                if f.name != "id" and getattr(hw, f.name) is not None
            ]
            raise MissingDevice(
                f"{program} needs a {name}; the robot's hardware ({type(hw).__name__}) has "
                f"none (it has: {', '.join(has) or 'nothing'})"
            )


def needs(
    *devices: str,
) -> Callable[
    [Callable[Concatenate[R, P], Awaitable[T]]], Callable[Concatenate[R, P], Awaitable[T]]
]:
    """Declare the devices a program needs (see the module docstring): the program, checked
    against ``robot.hw`` before its first line runs. ``program.needs`` lists them."""
    for name in devices:
        if not name.isidentifier():
            raise ValueError(f"needs: {name!r} is not a device's name")

    def declare(
        program: Callable[Concatenate[R, P], Awaitable[T]],
    ) -> Callable[Concatenate[R, P], Awaitable[T]]:
        name = getattr(program, "__name__", "this program")

        @functools.wraps(program)
        async def checked(robot: R, /, *args: P.args, **kwargs: P.kwargs) -> T:
            require(getattr(robot, "hw", None), *devices, program=f"program {name}")
            return await program(robot, *args, **kwargs)

        checked.needs = devices  # type: ignore[attr-defined]
        return checked

    return declare
