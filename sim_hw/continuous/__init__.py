"""Simulated hardware for mover robots: a continuous pymunk world behind the robots' HAL.

Public face (everything else is private and may change):

* world description — :class:`WorldSpec` and its parts, :func:`load_world`, the generators
  :func:`random_obstacles`, :func:`free_points` and
  :func:`double_corridor` (with :func:`corridor_paths`), and :class:`WorldFileError`;
* the world — :class:`World` (synchronous, deterministic) and :class:`WorldServer` (a world and
  its lock-step door, ``server.door``: lock-step or real time; robots ``join``, ``step`` and
  ``leave`` through it, and hooks on ``door.on_tick`` hear of every tick);
* backends of ``robots.hal`` — :func:`in_process` and :func:`remote` (over a ``mover.Node``),
  both built on :class:`SimHardware`; of ``robots.stigmergic``'s two kinds in process,
  :func:`eyebot_in_process` and :func:`footbot_in_process`;
* the ceiling layer — :class:`Ceiling` of :class:`EyeBotSpec` (eye-bots above the world and the
  devices between them and the foot-bots below); in a world process, eye-bots and foot-bots
  are robot processes of their own kinds (the ``eyebot`` and ``footbot`` backends, the areas
  of :class:`AreaSpec`);
* recording — :class:`Recorder`, :func:`read_recording`, :func:`plot_recording`;
* the world process — :func:`serve_world` (exports the world over zenoh).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from . import _spec
from ._spec import *  # noqa: F403  (the world description's parts, light: no pymunk, no numpy)

if TYPE_CHECKING:  # the type checker sees them all; at run time each is imported when used
    from sim_hw._lockstep import RobotDropped

    from ._ceiling import Below, Ceiling
    from ._contract import DT, STEPS_PER_TICK, TICK
    from ._generate import corridor_paths, double_corridor, free_points, random_obstacles
    from ._hardware import SimHardware, in_process, remote
    from ._kinds import eyebot_in_process, footbot_in_process
    from ._record import Recorder, plot_recording, read_recording
    from ._stepper import WorldServer, serve_world
    from ._world import World
    from ._worldfile import WorldFileError, load_world, parse_robot, parse_world

__all__ = [
    "DT",
    "STEPS_PER_TICK",
    "TICK",
    "Below",
    "Ceiling",
    "Recorder",
    "RobotDropped",
    "SimHardware",
    "World",
    "WorldFileError",
    "WorldServer",
    "corridor_paths",
    "double_corridor",
    "eyebot_in_process",
    "footbot_in_process",
    "free_points",
    "in_process",
    "load_world",
    "parse_robot",
    "parse_world",
    "plot_recording",
    "random_obstacles",
    "read_recording",
    "remote",
    "serve_world",
]
__all__ += _spec.__all__

#: Where each public name lives: a robot process that imports only its backend does not load
#: the world (pymunk) nor numpy through this package (issue 25's leaner robot processes).
_WHERE = {
    "Below": "._ceiling",
    "Ceiling": "._ceiling",
    "corridor_paths": "._generate",
    "double_corridor": "._generate",
    "free_points": "._generate",
    "random_obstacles": "._generate",
    "SimHardware": "._hardware",
    "in_process": "._hardware",
    "remote": "._hardware",
    "eyebot_in_process": "._kinds",
    "footbot_in_process": "._kinds",
    "Recorder": "._record",
    "plot_recording": "._record",
    "read_recording": "._record",
    "WorldServer": "._stepper",
    "serve_world": "._stepper",
    "DT": "._contract",
    "STEPS_PER_TICK": "._contract",
    "TICK": "._contract",
    "World": "._world",
    "WorldFileError": "._worldfile",
    "load_world": "._worldfile",
    "parse_robot": "._worldfile",
    "parse_world": "._worldfile",
    "RobotDropped": "sim_hw._lockstep",
}


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(where, __name__), name)
    globals()[name] = value  # once
    return value


def __dir__() -> list[str]:
    return sorted({*__all__, *(n for n in globals() if n.startswith("_"))})
