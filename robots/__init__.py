"""The robot side of mover: the hardware interface, the robot process, the library.

``robots.hal`` (a body in a continuous world) and ``robots.grid_hal`` (a robot on a grid)
declare what a robot needs from its hardware; ``Robot`` is what a program gets on one robot,
generic over that hardware (``Robot[Hardware]``, ``Robot[GridHardware]``, ``Robot[None]`` for a
workstation). ``robots.backend`` says how a robot process gets its hardware (a
``HardwareBackend`` per ``mover.hardware`` entry point) and ``robots.procedures`` what it
exports for each kind. The library of procedures and behaviours lives in subpackages.
"""

from ._robot import Robot

__all__ = ["Robot"]
