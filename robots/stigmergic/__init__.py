"""Cooperative stigmergic navigation in a heterogeneous swarm (Ducatelle, Di Caro and
Gambardella, "Cooperative stigmergic navigation in a heterogeneous robotic swarm", SAB 2010).

Eye-bots on the ceiling keep two stochastic policies each and instruct the foot-bots below them;
foot-bots follow the instructions between a source and a target and show with their LEDs where
they come from; eye-bots learn from what they see. Both behaviours are plain objects with a
``step`` over what the robot senses, their randomness from an injected generator:

* :class:`EyeBot` — sections 4.1–4.3 (:class:`Policy`, eq. 1, the draw rule);
* :class:`FootBot` — sections 4.3–4.4 (instructions, the forward/backward rule, LEDs).
"""

from robots.stigmergic._eyebot import EyeBot, FootBotSeen, Goal, Instruction, trip_weight
from robots.stigmergic._footbot import FootBot, FootCommand, FootPerception, Heard, Mode, Motion
from robots.stigmergic._leds import read as read_leds
from robots.stigmergic._leds import show as show_leds
from robots.stigmergic._policy import (
    DIRECTIONS,
    SPACING,
    Learning,
    Policy,
    direction_angle,
    direction_index,
)

__all__ = [
    "DIRECTIONS",
    "SPACING",
    "EyeBot",
    "FootBot",
    "FootBotSeen",
    "FootCommand",
    "FootPerception",
    "Goal",
    "Heard",
    "Instruction",
    "Learning",
    "Mode",
    "Motion",
    "Policy",
    "direction_angle",
    "direction_index",
    "read_leds",
    "show_leds",
    "trip_weight",
]
