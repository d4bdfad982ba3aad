"""A world with a ceiling behind the lock-step door: eye-bots and foot-bots as robots of it.

When a world file hangs eye-bots from the ceiling (``[[eyebots]]``), the world process serves
this stepper instead of the plain :class:`WorldStepper` (see ``WorldServer``). Both kinds are
robots of the door — each hands in one command per tick and gets its readings, so a lock-step
run repeats — but only foot-bots are bodies of the physics; eye-bots are on the
:class:`Ceiling`, which nothing on the ground can touch.

* An eye-bot joins with ``{"kind": "eyebot"}`` under an id of the file's eye-bots; its command
  (:class:`EyeCommand`) says what its IrRB cone sends, ``[θ_s, θ_t]``, from the next tick on;
  its readings (:class:`EyeReadings`) are what its downward camera sees.
* Every other robot is a foot-bot (``{"kind": "footbot"}``, or a plain ``sim`` robot): a body
  with its usual readings plus the upward devices (:class:`FootReadings`): the eye-bot whose
  cone it is in with that eye-bot's last instruction, the eye-bots its omnidirectional camera
  sees, and the area it is in.

So the broadcast travels through the world: an instruction handed in for tick n is applied
with the tick and heard in the readings after it, by the foot-bots under that eye-bot only.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Collection, Mapping
from typing import Any

from ._ceiling import Ceiling
from ._contract import EYEBOT, FOOTBOT, EyeReadings, FootReadings
from ._spec import RobotSpec
from ._stepper import WorldStepper
from ._world import World

log = logging.getLogger("sim_hw.continuous")


class SkyStepper(WorldStepper):
    """:class:`WorldStepper` with the world file's eye-bots on a :class:`Ceiling` above it."""

    def __init__(self, world: World) -> None:
        super().__init__(world)
        self.eyebots = {e.id: e for e in world.spec.eyebots}
        self.joined: set[str] = set()  # the eye-bots in
        self.sent: dict[str, tuple[float, float]] = {}  # eye-bot -> its instruction
        self.ceiling = Ceiling(world, (), world.spec.omni_range)
        self._readings: dict[str, Any] | None = None  # of every robot, as of the last change
        self._malformed = 0

    def robots(self) -> Collection[str]:
        """Ids of the foot-bots in the world and of the eye-bots in."""
        return self.world.robots.keys() | self.joined

    def prepare(self, robot: str, spec: Mapping[str, Any] | None) -> Any:
        """None for an eye-bot of the file (it takes no settings); a foot-bot's body otherwise
        (a :class:`RobotSpec`)."""
        settings = dict(spec or {})
        kind = settings.pop("kind", None)
        if kind not in (None, EYEBOT, FOOTBOT):
            raise ValueError(f"join({robot}): kind must be {EYEBOT!r} or {FOOTBOT!r}, not {kind!r}")
        if robot in self.eyebots:
            if kind == FOOTBOT or settings:
                raise ValueError(
                    f"join({robot}): {robot!r} is an eye-bot of this world (it takes no settings)"
                )
            return None
        if kind == EYEBOT:
            raise ValueError(
                f"join({robot}): this world has no eye-bot {robot!r} (its eye-bots: "
                f"{', '.join(sorted(self.eyebots)) or 'none'})"
            )
        return super().prepare(robot, settings)

    def admit(self, robot: str, prepared: RobotSpec | None) -> None:
        """Hang an eye-bot from the ceiling, or spawn a foot-bot."""
        self._readings = None
        if prepared is None:
            self.joined.add(robot)
            self._hang()
            return
        super().admit(robot, prepared)

    def start(self) -> None:
        """Re-create the foot-bots in id order (eye-bots do not move)."""
        self._readings = None
        super().start()

    def advance(self, commands: Mapping[str, Any]) -> None:
        """Take the eye-bots' instructions, set the foot-bots' commands, run one tick."""
        for robot, command in commands.items():
            if robot in self.joined:
                self._take(robot, command.get("irrb"))
            else:
                self.world.set_command(robot, command)
        self.world.step()
        self._readings = None

    def _take(self, eyebot: str, irrb: object) -> None:
        if irrb is None:
            return
        if (
            isinstance(irrb, list | tuple)
            and len(irrb) == 2
            and all(isinstance(a, int | float) and math.isfinite(a) for a in irrb)
        ):
            self.sent[eyebot] = (float(irrb[0]), float(irrb[1]))
            return
        self._malformed += 1  # from another process: never a reason to stop the world
        if self._malformed == 1:
            log.warning("eye-bot %s sent a malformed instruction %.60r (ignored)", eyebot, irrb)

    def readings(self, robot: str) -> Any:
        """``robot``'s readings from the end of the last tick (eye-bot's or foot-bot's)."""
        if self._readings is None:
            self._readings = self._sense()
        return self._readings[robot]

    def spec_of(self, robot: str) -> dict[str, Any]:
        """An eye-bot's camera and cone; a foot-bot's body and the range of its omni camera."""
        if robot in self.joined:
            eye = self.eyebots[robot]
            return {"kind": EYEBOT, "view": eye.view, "cone": eye.cone}
        return {**super().spec_of(robot), "kind": FOOTBOT, "omni_range": self.ceiling.omni_range}

    def remove(self, robot: str) -> None:
        """Take ``robot`` out (an eye-bot's broadcast ends with it)."""
        self._readings = None
        if robot in self.joined:
            self.joined.discard(robot)
            self.sent.pop(robot, None)
            self._hang()
            return
        super().remove(robot)

    def _hang(self) -> None:
        """The ceiling of the eye-bots in (in file order): only they are seen and heard."""
        eyes = [e for e in self.world.spec.eyebots if e.id in self.joined]
        self.ceiling = Ceiling(self.world, eyes, self.world.spec.omni_range)

    def _sense(self) -> dict[str, Any]:
        world, ceiling = self.world, self.ceiling
        ceiling.sense()
        out: dict[str, Any] = {}
        for eid in self.joined:
            below = [
                [*b.beacon, *(b.front if b.front is not None else (None, None)), b.led]
                for b in ceiling.camera(eid)
            ]
            eye: EyeReadings = {"tick": world.tick, "t": world.time, "below": below}
            out[eid] = eye
        for rid in world.robots:
            above = ceiling.above(rid)
            heard = None
            if above is not None and above[0] in self.sent:
                heard = [above[0], above[1], *self.sent[above[0]]]
            foot: FootReadings = {
                **world.readings(rid),
                "above": heard,
                "omni": [[d, b] for d, b in ceiling.omni(rid)],
                "area": self._area(rid),
            }
            out[rid] = foot
        return out

    def _area(self, robot: str) -> str | None:
        x, y, _ = self.world.pose(robot)  # the area sensor: a floor colour under the robot
        for area in self.world.spec.areas:
            if math.hypot(x - area.center[0], y - area.center[1]) <= area.radius:
                return area.id
        return None
