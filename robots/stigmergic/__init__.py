"""Cooperative stigmergic navigation in a heterogeneous swarm (Ducatelle, Di Caro and
Gambardella, "Cooperative stigmergic navigation in a heterogeneous robotic swarm", SAB 2010).

Eye-bots on the ceiling keep two stochastic policies each and instruct the foot-bots below them;
foot-bots follow the instructions between a source and a target and show with their LEDs where
they come from; eye-bots learn from what they see. Both behaviours are plain objects with a
``step`` over what the robot senses, their randomness from an injected generator:

* :class:`EyeBot` — sections 4.1–4.3 (:class:`Policy`, eq. 1, the draw rule);
* :class:`FootBot` — sections 4.3–4.4 (instructions, the forward/backward rule, LEDs).

As robot processes: each kind's hardware (:class:`EyeBotHardware`, :class:`FootBotHardware`:
protocols of its devices, no ground truth) and a loop that drives its behaviour on it
(:func:`eyebot_loop`, :func:`footbot_loop`).
"""

from robots.stigmergic._eyebot import (
    EyeBot,
    FootBotSeen,
    Goal,
    Instruction,
    Reading,
    trip_weight,
)
from robots.stigmergic._footbot import FootBot, FootCommand, FootPerception, Heard, Mode, Motion
from robots.stigmergic._hal import (
    AreaSensor,
    DownCamera,
    EyeBotHardware,
    FootBotHardware,
    Hanging,
    IrRB,
    OmniCamera,
    Spot,
    UpCamera,
    eyebot_procedures,
    footbot_procedures,
    footbot_seen,
    obstacle_bearing,
)
from robots.stigmergic._leds import read as read_leds
from robots.stigmergic._leds import show as show_leds
from robots.stigmergic._loops import (
    AVOID,
    Trip,
    eyebot_loop,
    footbot_loop,
    perceive,
    travel_times,
)
from robots.stigmergic._policy import (
    DIRECTIONS,
    SPACING,
    Learning,
    Policy,
    direction_angle,
    direction_index,
)

__all__ = [
    "AVOID",
    "DIRECTIONS",
    "SPACING",
    "AreaSensor",
    "DownCamera",
    "EyeBot",
    "EyeBotHardware",
    "FootBot",
    "FootBotHardware",
    "FootBotSeen",
    "FootCommand",
    "FootPerception",
    "Goal",
    "Hanging",
    "Heard",
    "Instruction",
    "IrRB",
    "Learning",
    "Mode",
    "Motion",
    "OmniCamera",
    "Policy",
    "Reading",
    "Spot",
    "Trip",
    "UpCamera",
    "direction_angle",
    "direction_index",
    "eyebot_loop",
    "eyebot_procedures",
    "footbot_loop",
    "footbot_procedures",
    "footbot_seen",
    "obstacle_bearing",
    "perceive",
    "read_leds",
    "show_leds",
    "travel_times",
    "trip_weight",
]
