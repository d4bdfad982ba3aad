"""Simulated hardware for mover robots, in two wings over one lock-step door.

* :mod:`sim_hw.continuous` — the pymunk world: bodies, devices, world files, its robot-side
  backend, recording;
* :mod:`sim_hw.grid` — the grid world: grids, files, generators (the Linardakis maze among
  them), floor marks and pheromone, its robot-side backend.

The continuous wing's public face is re-exported here, since it is the default world.
"""

from sim_hw._process import STATE_TOPIC
from sim_hw.continuous import (
    DT,
    STEPS_PER_TICK,
    TICK,
    BoxSpec,
    CameraSpec,
    ImmovableSpec,
    MarkerSpec,
    ObstacleSpec,
    OdometrySpec,
    Recorder,
    RobotDropped,
    RobotSpec,
    SimHardware,
    SonarSpec,
    World,
    WorldFileError,
    WorldServer,
    WorldSpec,
    double_corridor,
    in_process,
    load_world,
    parse_robot,
    parse_world,
    plot_recording,
    random_obstacles,
    read_recording,
    remote,
    serve_world,
)

__all__ = [
    "DT",
    "STATE_TOPIC",
    "STEPS_PER_TICK",
    "TICK",
    "BoxSpec",
    "CameraSpec",
    "ImmovableSpec",
    "MarkerSpec",
    "ObstacleSpec",
    "OdometrySpec",
    "Recorder",
    "RobotDropped",
    "RobotSpec",
    "SimHardware",
    "SonarSpec",
    "World",
    "WorldFileError",
    "WorldServer",
    "WorldSpec",
    "double_corridor",
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
