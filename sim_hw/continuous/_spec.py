"""Plain descriptions of a continuous world and its robots (no pymunk here).

A :class:`WorldSpec` is what a world file parses into and what the generators build; the
:class:`sim_hw.World` turns it into pymunk bodies. Every field has an SI unit: metres, seconds,
radians, kilograms, newtons.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

#: The parts of a world description, re-exported by ``sim_hw.continuous`` (named here once).
__all__ = [
    "AreaSpec",
    "BoxSpec",
    "CameraSpec",
    "EyeBotSpec",
    "ImmovableSpec",
    "MarkerSpec",
    "ObstacleSpec",
    "OdometrySpec",
    "RobotSpec",
    "SonarSpec",
    "WorldSpec",
]

Vec = tuple[float, float]
Pose = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class SonarSpec:
    """A ring of ``rays`` range sensors spread evenly around the robot, first one ahead."""

    rays: int = 8
    max_range: float = 3.0
    noise: float = 0.0
    """Standard deviation of the additive Gaussian noise on a range that hits something (m)."""

    def angles(self) -> tuple[float, ...]:
        """Ray directions relative to the heading."""
        return tuple(2.0 * math.pi * i / self.rays for i in range(self.rays))


@dataclass(frozen=True, slots=True)
class CameraSpec:
    """A camera that reports robots and objects whose centre is within range and view."""

    max_range: float = 3.0
    fov: float = math.radians(120.0)
    occlusion: bool = True
    """Whether walls and static obstacles hide what is behind them."""


@dataclass(frozen=True, slots=True)
class OdometrySpec:
    """Noise of dead reckoning, as standard deviations proportional to the motion."""

    trans_noise: float = 0.0
    """Metres of error per metre travelled."""
    rot_noise: float = 0.0
    """Radians of error per radian turned."""
    drift: float = 0.0
    """Radians of heading error per metre travelled."""


@dataclass(frozen=True, slots=True)
class RobotSpec:
    """A disc robot with a differential drive limited by force.

    ``force`` bounds the drive (the most the wheels push, traction included): whether the robot
    can move an object is physics, not a flag. ``pose`` ``None`` means "take a spawn point".
    """

    pose: Pose | None = None
    radius: float = 0.15
    mass: float = 5.0
    force: float = 70.0
    track: float = 0.3
    max_speed: float = 0.5
    max_turn: float = 2.0
    sonar: SonarSpec | None = field(default_factory=SonarSpec)
    camera: CameraSpec | None = field(default_factory=CameraSpec)
    odometry: OdometrySpec = field(default_factory=OdometrySpec)
    radio: bool = True
    led: str = ""


@dataclass(frozen=True, slots=True)
class ObstacleSpec:
    """A static wall piece: ``box`` (center, size, angle), ``circle`` (center, radius) or
    ``segment`` (a, b, radius)."""

    shape: str
    center: Vec = (0.0, 0.0)
    size: Vec = (0.0, 0.0)
    angle: float = 0.0
    radius: float = 0.0
    a: Vec = (0.0, 0.0)
    b: Vec = (0.0, 0.0)


@dataclass(frozen=True, slots=True)
class BoxSpec:
    """A movable box sliding on the floor with Coulomb friction ``friction`` (μ)."""

    id: str
    center: Vec
    size: Vec
    mass: float
    friction: float = 0.5
    angle: float = 0.0
    status: str = ""


@dataclass(frozen=True, slots=True)
class ImmovableSpec:
    """An object the camera reports (kind ``immovable``) that no force moves."""

    id: str
    center: Vec
    shape: str = "box"
    size: Vec = (0.5, 0.5)
    radius: float = 0.25
    angle: float = 0.0
    status: str = ""


@dataclass(frozen=True, slots=True)
class MarkerSpec:
    """Something seen but not touched: a ``target``, a ``resource`` cell or a ``beacon``.

    A marker with ``hears`` > 0 is a passive beacon a robot can mark (Sutantyo et al., V-B:
    the finder sends "a specific message content to the target to turn on the repelling
    signal"): a robot whose LED shows ``mark:<id>`` within ``hears`` metres of its centre
    marks it, and from then on its status reads ``marked``.
    """

    kind: str
    id: str
    center: Vec
    radius: float = 0.2
    status: str = ""
    hears: float = 0.0
    """Range (m) within which a robot's ``mark:<id>`` LED message marks it (0: never)."""


@dataclass(frozen=True, slots=True)
class EyeBotSpec:
    """An eye-bot on the ceiling above ``center``, its reference direction θ0 = ``heading``;
    its camera sees a disc of radius ``view`` on the ground, its broadcast reaches ``cone``
    (Ducatelle et al.; see ``sim_hw.continuous._ceiling``)."""

    id: str
    center: Vec
    heading: float = 0.0
    view: float = 1.0
    cone: float = 0.5


@dataclass(frozen=True, slots=True)
class AreaSpec:
    """A disc of floor a robot's area sensor tells apart (the source or the target, say)."""

    id: str
    center: Vec
    radius: float = 1.0


@dataclass(frozen=True, slots=True)
class WorldSpec:
    """A rectangular arena [0, w] × [0, h] with walls, and what is in it."""

    size: Vec = (10.0, 10.0)
    name: str = "world"
    cell: float = 0.25
    """Side of a floor cell (m)."""
    robot: RobotSpec = field(default_factory=RobotSpec)
    """Defaults for robots that join without saying otherwise."""
    robots: dict[str, RobotSpec] = field(default_factory=dict)
    """Robots named in the file: their spawn poses and settings (they join at run time)."""
    obstacles: tuple[ObstacleSpec, ...] = ()
    boxes: tuple[BoxSpec, ...] = ()
    immovables: tuple[ImmovableSpec, ...] = ()
    markers: tuple[MarkerSpec, ...] = ()
    floor: tuple[tuple[int, int, int, str], ...] = ()
    """Preset floor cells: (column, row, value, colour)."""
    eyebots: tuple[EyeBotSpec, ...] = ()
    """Eye-bots on the ceiling (robot processes of their own kind; not bodies of the physics)."""
    areas: tuple[AreaSpec, ...] = ()
    """Areas the robots' area sensors tell apart (with eye-bots: ``source`` and ``target``)."""
    omni_range: float = 3.0
    """How far the robots' omnidirectional cameras see eye-bots (m, horizontally)."""
