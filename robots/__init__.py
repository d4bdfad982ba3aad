"""The robot side of mover: the hardware interface, the robot process, the library.

``robots.hal`` declares what a robot needs from its hardware; ``Robot`` is what a program gets
on one robot. The library of procedures and behaviours lives in subpackages.
"""

from ._robot import Robot

__all__ = ["Robot"]
