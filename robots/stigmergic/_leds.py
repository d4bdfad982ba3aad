"""The foot-bot's two light signals as one LED status string (the HAL's ``Led.show``).

A foot-bot shows its beacon's colour (``beacon``: plain; ``avoid``: avoiding an obstacle) and
its front LED's (``target`` or ``source``: its goal; ``off``), as ``"<beacon>/<front>"``, e.g.
``"avoid/off"``. The world shows them to eye-bots' cameras; one codec for both sides.
"""

from __future__ import annotations

from ._eyebot import Goal

PLAIN = "beacon"
AVOID = "avoid"
OFF = "off"


def show(avoiding: bool, front: Goal | None) -> str:
    """The LED status for a beacon (avoiding or not) and a front LED (a goal, or off)."""
    return f"{AVOID if avoiding else PLAIN}/{front.value if front is not None else OFF}"


def read(status: str) -> tuple[bool, Goal | None] | None:
    """``(avoiding, front)`` from an LED status; None if it is not a foot-bot's."""
    beacon, sep, front = status.partition("/")
    if not sep or beacon not in (PLAIN, AVOID):
        return None
    if front == OFF:
        return (beacon == AVOID, None)
    try:
        return (beacon == AVOID, Goal(front))
    except ValueError:
        return None
