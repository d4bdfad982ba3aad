"""Simulated hardware for mover robots, in two wings over one lock-step door.

* :mod:`sim_hw.continuous` — the pymunk world: bodies, devices, world files, its robot-side
  backend, recording;
* :mod:`sim_hw.grid` — the grid world: grids, files, generators (the Linardakis maze among
  them), floor marks and pheromone, its robot-side backend.

The continuous wing's public face is re-exported here, since it is the default world.
"""

from sim_hw import continuous as _continuous
from sim_hw._link import WorldLost
from sim_hw._process import STATE_TOPIC
from sim_hw.continuous import *  # noqa: F403

__all__ = ["STATE_TOPIC", "WorldLost"]
__all__ += _continuous.__all__
