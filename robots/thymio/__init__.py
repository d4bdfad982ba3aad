"""A Thymio II behind the HAL, over the Aseba protocol (``--hardware thymio``).

The Thymio II (Mobsya/EPFL) is a small differential-drive robot; it speaks Aseba over its USB
serial port or its wireless dongle, and Aseba Playground simulates it over TCP with the same
protocol. This package maps it onto ``robots.hal`` (see docs/thymio.md): drive with a stated
calibration, the 7 proximity sensors as ranges, the ground sensors, odometry by dead
reckoning, the LEDs, the buttons, a real-time clock at a fixed control rate.

Positions for the radio: by default the odometry (it drifts). A lab with a tracking system
passes ``locator`` to :func:`connect`: a function of the odometry that returns any
:class:`robots.hal.RadioLocator` (``position() -> (x, y, heading) | None``), e.g. one that
reads the tracker's latest pose for this robot.
"""

from robots.library import needs

from ._behaviours import ProxWander, drive_to, wander_until
from ._calibration import PROX_ANGLES, Calibration
from ._devices import BUTTONS, Buttons, Ground, Leds, Proximity
from ._hardware import MissingDevice, OdometryLocator, ThymioHardware, connect, require

__all__ = [
    "BUTTONS",
    "PROX_ANGLES",
    "Buttons",
    "Calibration",
    "Ground",
    "Leds",
    "MissingDevice",
    "OdometryLocator",
    "ProxWander",
    "Proximity",
    "ThymioHardware",
    "connect",
    "drive_to",
    "needs",
    "require",
    "wander_until",
]
