"""A robot process with test programs, for the idle and liveness tests.

Run as ``python -m tests.robots.program_robot NAME``: the robot process of ``mover robot``
(``robots.process.run_robot``, ``sim`` hardware, team and zenoh settings from the MOVER_*
environment) hosting one program, ``walk``. Prints ``READY`` once its hardware is up.
"""

from __future__ import annotations

import time
from typing import Any

from tests.helpers.robot_main import run_test_robot


async def walk(
    robot: Any, team: Any, ticks: int = 20, staller: str = "", stall: float = 0.0
) -> Any:
    """Drive ahead for ``ticks`` ticks; the member named ``staller`` blocks its event loop for
    ``stall`` wall seconds half way (as on a starved CPU: zenoh's threads, and with them the
    member's lease, live on). Returns the simulated times it started and ended at."""
    hw = robot.hw
    start = hw.clock.now()
    for i in range(ticks):
        hw.drive.set_velocity(0.2, 0.0)
        if robot.id == staller and i == ticks // 2:
            time.sleep(stall)  # noqa: ASYNC251 -- the point: a loop that does not run
        await hw.clock.tick()
    hw.drive.stop()
    return {"start": start, "end": hw.clock.now()}


if __name__ == "__main__":
    run_test_robot({"walk": walk})
