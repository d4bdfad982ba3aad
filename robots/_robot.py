"""What a program gets on one robot."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

from mover import Node

from .hal import Hardware


@dataclass
class Robot:
    """One robot as its programs see it: its name, its hardware, its node.

    ``node`` is None when a behaviour runs without a network (unit tests, fast experiments);
    ``hw`` is None on a member without a body (a workstation).
    """

    id: str
    hw: Hardware
    node: Node | None = None
    kind: str = "robot"
    log: logging.Logger = field(init=False)

    def __post_init__(self) -> None:
        self.log = logging.getLogger(f"robots.{self.id}")
