"""The ``thymio`` hardware backend: a Thymio II over the Aseba protocol.

Installed as the ``mover.hardware`` entry point ``thymio``::

    mover robot --name t1 --hardware thymio --option link=tcp:127.0.0.1:33333
    mover robot --name t1 --hardware thymio --option link=/dev/ttyACM0

``link`` (required) is ``tcp:HOST:PORT`` (a Playground robot, or ``asebaswitch``) or a serial
device (the robot's USB cable, or a wireless dongle paired with it alone); ``node`` the Aseba
node id (needed when several robots share one link: a dongle paired with several robots,
served to one process each by ``asebaswitch``; ``python -m robots.thymio.nodes LINK`` lists
them); ``tick_period`` the control period in seconds (default
0.05); ``timeout`` how long an answer may take before the robot counts as lost (default 2).
The robot's spec gives ``pose`` (where odometry starts, and so the radio's position) and
``calibration`` (``robots.thymio.Calibration``). It offers the procedures of a robot with a
body (:func:`robots.procedures.body_procedures`) and ``robot.thymio``: the raw readings.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from robots.procedures import body_procedures

from ._hardware import ThymioHardware, connect

if TYPE_CHECKING:
    from mover import Node
    from robots.backend import HardwareBackend


class ThymioBackend:
    """Connects to a Thymio II; a :class:`robots.backend.HardwareBackend`."""

    options = frozenset({"link", "node", "tick_period", "timeout"})

    async def connect(
        self, node: Node, robot_id: str, spec: Mapping[str, Any], **options: Any
    ) -> ThymioHardware:
        """Connect to the Thymio at option ``link`` (see the module docstring)."""
        if "link" not in options:
            raise ValueError(
                "hardware backend 'thymio' needs the option link (tcp:HOST:PORT or a serial "
                "device): --option link=tcp:127.0.0.1:33333"
            )
        aseba_node = options.get("node")
        return await connect(
            robot_id,
            str(options["link"]),
            node=None if aseba_node is None else int(aseba_node),
            spec=dict(spec),
            tick_period=float(options.get("tick_period", 0.05)),
            timeout=float(options.get("timeout", 2.0)),
        )

    def procedures(self, hw: ThymioHardware) -> Mapping[str, Callable[..., Any]]:
        """A body's ``robot.pose``, ``robot.stop``, ``robot.sense``, and ``robot.thymio``."""

        def thymio() -> dict[str, Any]:
            """The Thymio's own readings: raw proximity, ground reflectance, buttons."""
            return {
                "prox": list(hw.sonar.raw()) if hw.sonar is not None else None,  # type: ignore[attr-defined]
                "ground": list(hw.ground.reflectance()),
                "buttons": sorted(hw.buttons.pressed()),
            }

        return {**body_procedures(hw), "robot.thymio": thymio}


BACKEND: HardwareBackend[ThymioHardware] = ThymioBackend()
