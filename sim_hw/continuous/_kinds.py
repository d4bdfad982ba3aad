"""The HAL of eye-bots and foot-bots (``robots.stigmergic``) on a world with a ceiling.

Both are :class:`SimHardware` — the same command buffer and clock over a link to the world
(in process or over zenoh) — with the devices of their kind as views of its readings
(``_contract``: :class:`EyeReadings`, :class:`FootReadings`). An eye-bot's command carries only
its IrRB instruction; a foot-bot's is a ground robot's. :func:`eyebot_in_process`,
:func:`footbot_in_process` and :func:`join_remote` join a world with a ceiling as one kind or
the other; the world refuses a join of the wrong kind (``_skyworld``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from mover import RemoteError
from robots.hal import Sonar
from robots.stigmergic import EyeBotHardware, FootBotHardware, Goal, Heard, Instruction, Spot
from sim_hw import _link

from ._contract import EYEBOT, FOOTBOT, Command
from ._hardware import SimHardware, _Clock, _Drive, _Led, _Odometry, _Radio, _Sonar

if TYPE_CHECKING:
    from mover import Node

    from ._stepper import WorldServer


class _Kind(SimHardware):
    @property
    def got(self) -> Any:
        """The last readings, with the keys of this kind (``_contract``)."""
        return self.readings


class EyeBotSim(_Kind):
    """An eye-bot's hardware: its camera's readings in, its instruction out."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._irrb: list[float] | None = None
        self.view = float(self.spec["view"])
        self.cone = float(self.spec["cone"])

    def _command(self) -> Command:
        command: dict[str, Any] = {} if self._irrb is None else {"irrb": self._irrb}
        return command  # type: ignore[return-value]  # an eye-bot's (_contract.EyeCommand)

    def send(self, instruction: Instruction) -> None:
        """Broadcast ``instruction`` from the next tick on."""
        self._irrb = [float(instruction.to_source), float(instruction.to_target)]

    def below(self) -> tuple[Spot, ...]:
        """The foot-bots the downward camera saw at the last tick."""
        out = []
        for bx, by, fx, fy, led in self.got.get("below", ()):
            front = None if fx is None or fy is None else (float(fx), float(fy))
            out.append(Spot((float(bx), float(by)), front, str(led)))
        return tuple(out)

    def eyebot(self) -> EyeBotHardware:
        """The eye-bot's HAL bundle."""
        return EyeBotHardware(
            id=self.id, clock=_Clock(self), camera=_Down(self), irrb=_IrRB(self), drive=_Hang()
        )


class FootBotSim(_Kind):
    """A foot-bot's hardware: a ground robot's, with the devices that look up."""

    def above(self) -> Heard | None:
        """The eye-bot above and its instruction, as the last readings have them."""
        got = self.got.get("above")
        if not got:
            return None
        eyebot, reference, to_source, to_target = got
        return Heard(str(eyebot), float(reference), float(to_source), float(to_target))

    def eyebots(self) -> tuple[tuple[float, float], ...]:
        """(distance, bearing) of the eye-bots the omnidirectional camera saw."""
        return tuple((float(d), float(b)) for d, b in self.got.get("omni", ()))

    def area(self) -> Goal | None:
        """The area under the robot: the source, the target, or neither."""
        got = self.got.get("area")
        return Goal(got) if got in (Goal.SOURCE.value, Goal.TARGET.value) else None

    def footbot(self) -> FootBotHardware:
        """The foot-bot's HAL bundle (its sonar is required)."""
        sonar = self.spec.get("sonar")
        if not sonar:
            raise ValueError(f"foot-bot {self.id!r} has no sonar (its proximity ring)")
        ring: Sonar = _Sonar(self, sonar)
        return FootBotHardware(
            id=self.id,
            clock=_Clock(self),
            drive=_Drive(self),
            odometry=_Odometry(self),
            sonar=ring,
            led=_Led(self),
            up=_Up(self),
            omni=_Omni(self, float(self.spec.get("omni_range", 0.0))),
            area=_Area(self),
            radio=_Radio(self) if self.spec.get("radio", True) else None,
        )


class _Down:
    def __init__(self, hw: EyeBotSim) -> None:
        self.view = hw.view
        self.below = hw.below


class _IrRB:
    def __init__(self, hw: EyeBotSim) -> None:
        self.cone = hw.cone
        self.send = hw.send


class _Hang:
    def stop(self) -> None:
        """An eye-bot hangs still: nothing to stop."""


class _Up:
    def __init__(self, hw: FootBotSim) -> None:
        self.above = hw.above


class _Omni:
    def __init__(self, hw: FootBotSim, max_range: float) -> None:
        self.max_range = max_range
        self.eyebots = hw.eyebots


class _Area:
    def __init__(self, hw: FootBotSim) -> None:
        self.area = hw.area


def _kind_of(joined: Mapping[str, Any], robot_id: str, kind: str) -> None:
    got = joined["spec"].get("kind")
    if got != kind:
        raise ValueError(f"{robot_id!r} joined as a {got or 'plain robot'}, not as a {kind}")


async def eyebot_in_process(server: WorldServer, robot_id: str) -> EyeBotHardware:
    """Join ``server`` (a ``WorldServer`` in this process) as the eye-bot ``robot_id``."""
    joined, link = await _link.in_process(server.door, robot_id, {"kind": EYEBOT})
    _kind_of(joined, robot_id, EYEBOT)
    return EyeBotSim(robot_id, joined["spec"], joined["readings"], link).eyebot()


async def footbot_in_process(
    server: WorldServer, robot_id: str, spec: Mapping[str, Any] | None = None
) -> FootBotHardware:
    """Join ``server`` (a ``WorldServer`` in this process) as the foot-bot ``robot_id``."""
    joined, link = await _link.in_process(server.door, robot_id, {**(spec or {}), "kind": FOOTBOT})
    _kind_of(joined, robot_id, FOOTBOT)
    return FootBotSim(robot_id, joined["spec"], joined["readings"], link).footbot()


async def join_remote(
    node: Node,
    robot_id: str,
    kind: str,
    spec: Mapping[str, Any] | None = None,
    *,
    world: str = "world",
    call_timeout: float = 30.0,
) -> EyeBotHardware | FootBotHardware:
    """Join the world process ``world`` over ``node`` as an eye-bot or a foot-bot (``kind``).

    A join the world refuses (no such eye-bot, a wrong kind, bad settings) raises ValueError
    with the world's reason: the robot process says it in one line.
    """
    try:
        joined, link = await _link.remote(
            node, robot_id, {**(spec or {}), "kind": kind}, world=world, call_timeout=call_timeout
        )
    except RemoteError as exc:
        if exc.remote_type not in ("ValueError", "WorldFileError"):
            raise
        raise ValueError(f"world {world!r} refused {robot_id!r}: {exc.message}") from None
    _kind_of(joined, robot_id, kind)
    if kind == EYEBOT:
        return EyeBotSim(robot_id, joined["spec"], joined["readings"], link).eyebot()
    return FootBotSim(robot_id, joined["spec"], joined["readings"], link).footbot()
