"""What a program gets on one robot."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Generic

from mover import Node

from .hal import Hardware

if TYPE_CHECKING:
    # A default (PEP 696) so that a bare ``Robot`` — the library's robot with a body — stays
    # ``Robot[Hardware]``; typing.TypeVar takes ``default`` only from Python 3.13 on, and the
    # type checker is the only reader of it.
    from typing_extensions import TypeVar

    H = TypeVar("H", default=Hardware)
else:
    from typing import TypeVar

    H = TypeVar("H")


@dataclass
class Robot(Generic[H]):
    """One robot as its programs see it: its name, its hardware, its node.

    Generic over its hardware: ``Robot[Hardware]`` (a body in a continuous world; a bare
    ``Robot`` means that), ``Robot[GridHardware]`` (a robot on a grid, ``robots.grid_hal``),
    ``Robot[None]`` (a member without a body: a workstation). ``node`` is None when a behaviour
    runs without a network (unit tests, fast experiments).
    """

    id: str
    hw: H
    node: Node | None = None
    kind: str = "robot"
    log: logging.Logger = field(init=False)

    def __post_init__(self) -> None:
        self.log = logging.getLogger(f"robots.{self.id}")
