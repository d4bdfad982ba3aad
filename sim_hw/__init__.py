"""Simulated hardware for mover robots, in two wings over one lock-step door.

* :mod:`sim_hw.continuous` — the pymunk world: bodies, devices, world files, its robot-side
  backend, recording;
* :mod:`sim_hw.grid` — the grid world: grids, files, generators (the Linardakis maze among
  them), floor marks and pheromone, its robot-side backend.

The continuous wing's public face is re-exported here, since it is the default world.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from sim_hw import continuous as _continuous
from sim_hw._link import WorldLost

if TYPE_CHECKING:  # at run time the continuous wing's names are imported when used
    from sim_hw._process import STATE_TOPIC
    from sim_hw.continuous import *  # noqa: F403

__all__ = ["STATE_TOPIC", "WorldLost"]
__all__ += _continuous.__all__


def __getattr__(name: str) -> Any:
    if name == "STATE_TOPIC":
        from sim_hw._process import STATE_TOPIC as topic

        return topic
    return getattr(_continuous, name)  # (AttributeError, named, for what it does not have)


def __dir__() -> list[str]:
    return sorted({*__all__, *(n for n in globals() if n.startswith("_"))})
