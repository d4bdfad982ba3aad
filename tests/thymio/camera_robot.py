"""A Thymio robot process hosting a program that needs a camera, for the missing-device test.

Run as ``python -m tests.thymio.camera_robot NAME LINK``: ``mover robot``'s process
(``robots.process.run_robot``) on ``--hardware thymio`` with ``link=LINK``, hosting ``look``,
which declares ``@needs("camera")``. Prints ``READY`` once the Thymio is connected.
"""

from __future__ import annotations

import sys
from typing import Any

from robots import Robot
from robots.library import needs
from robots.thymio import ThymioHardware
from tests.helpers.robot_main import run_test_robot


@needs("camera")
async def look(robot: Robot[ThymioHardware], team: Any) -> int:
    """How many things the camera sees (never reached on a Thymio: it has no camera)."""
    hw: Any = robot.hw
    return len(hw.camera.sightings())


if __name__ == "__main__":
    run_test_robot({"look": look}, hardware="thymio", options={"link": sys.argv[2]})
