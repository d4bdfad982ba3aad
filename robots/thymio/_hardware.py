"""A Thymio II as ``robots.hal`` hardware: connect over Aseba, read and drive it each tick.

:func:`connect` opens the link (``_link``), checks that the node is a Thymio II (its
variables), loads the small LED program (:func:`led_program`), stops the motors and returns a
:class:`ThymioHardware`: a :class:`robots.hal.Hardware` (clock, drive, odometry, the proximity
sensors as its sonar, the top LED as its LED, the radio's locator) with the Thymio's own
devices beside (ground sensors, buttons, both LED groups). It has no camera, bumper, floor
cells or push test: those are None, and a program that declares it needs one
(``robots.library.needs``) fails as it starts, naming it in one line.

Each tick costs one ``GET_VARIABLES`` of the words from ``button.backward`` to the LED
program's copy of the lights it applied (59 words on the Playground's firmware) and its
answer, plus one ``SET_VARIABLES`` per command that changed.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from robots.hal import Hardware, Pose, RadioLocator
from robots.library import MissingDevice, require

from . import _aseba as aseba
from ._calibration import Calibration
from ._clock import ThymioClock
from ._devices import Buttons, Ground, Leds, Proximity, Readings, ThymioDrive, ThymioOdometry
from ._link import HOST, Address, AsebaLink

__all__ = ["MissingDevice", "ThymioHardware", "connect", "led_program", "require"]

#: The variables read each tick, and the motor targets written.
SENSED = (
    "button.backward",
    "button.left",
    "button.center",
    "button.forward",
    "button.right",
    "prox.horizontal",
    "prox.ground.delta",
    "motor.left.speed",
    "motor.right.speed",
)
DRIVEN = ("motor.left.target", "motor.right.target")
LED_WORDS = 11
"""The words the LED program applies (top r, g, b, the circle's 8), and copies after them."""
LED_EVENT = "buttons"
"""The firmware's periodic event (20 Hz on the robot) the LED program runs on."""


@dataclass(frozen=True, slots=True, kw_only=True)
class ThymioHardware(Hardware):
    """A Thymio II: the HAL's :class:`~robots.hal.Hardware` and its own devices.

    ``sonar`` is the 7 proximity sensors (:class:`~robots.thymio.Proximity`, about 12 cm of
    reach), ``led`` the top LED; ``ground``, ``buttons`` and ``leds`` (top and circle) are the
    Thymio's. ``camera``, ``bumper``, ``floor`` and ``push`` are None: it has none.
    """

    ground: Ground
    buttons: Buttons
    leds: Leds
    calibration: Calibration
    link: str
    aseba: AsebaLink
    """The Aseba conversation itself, for what the HAL does not map: any variable by name
    (``aseba.write("button.center", (1,))``, ``await aseba.read(offset, size, timeout)``)."""


def led_program(link: AsebaLink, at: int) -> tuple[int, ...]:
    """Bytecode that, on each ``buttons`` event, sets the top LED from the words ``at``..
    ``at+2`` and the circle from ``at+3``..``at+10`` (the Thymio sets its LEDs through native
    functions only, so a host writes those words and this program applies them), then copies
    the 11 words it applied to ``at+11``..``at+21``: what the host reads back as the lights
    shown (the LEDs themselves are not readable over Aseba).

    Aseba bytecode: a table of (event, address) after its own length, then for each native
    call the addresses of its arguments pushed last first (``push.s``, 0x1000), the call
    (``callnat``, 0xC000); each copy a ``load`` (0x3000) and a ``store`` (0x4000); ``stop``
    (0x0000).
    """
    event = 0xFFFE - link.events.index(LED_EVENT)
    code: list[int] = [3, event, 3]
    for native, first, count in (("leds.top", at, 3), ("leds.circle", at + 3, 8)):
        code += [0x1000 | (first + i) for i in reversed(range(count))]
        code.append(0xC000 | link.natives.index(native))
    for i in range(LED_WORDS):
        code += [0x3000 | (at + i), 0x4000 | (at + LED_WORDS + i)]
    code.append(0x0000)
    return tuple(code)


class _Thymio:
    """The connection's side of the devices: one exchange per tick (see the module)."""

    def __init__(
        self, link: AsebaLink, cal: Calibration, drive: ThymioDrive, leds: Leds, timeout: float
    ) -> None:
        self.link, self.cal, self.drive, self.leds, self.timeout = link, cal, drive, leds, timeout
        offsets = [link.variables[n] for n in SENSED]
        self.led_words = link.table_size
        self.start = min(o for o, _ in offsets)
        end = max(max(o + s for o, s in offsets), self.led_words + 2 * LED_WORDS)
        self.length = end - self.start
        self.sent_targets: tuple[int, int] | None = None
        self.sent_leds: tuple[int, ...] | None = None

    def send(self) -> None:
        if self.drive.targets != self.sent_targets:
            self.sent_targets = self.drive.targets
            self.link.write(DRIVEN[0], self.drive.targets[:1])
            self.link.write(DRIVEN[1], self.drive.targets[1:])
        if self.leds.words() != self.sent_leds:
            self.sent_leds = self.leds.words()
            self.link.write_at(self.led_words, self.sent_leds)

    async def exchange(self) -> Readings:
        self.send()
        words = await self.link.read(self.start, self.length, self.timeout)
        return self.parse(words, time.time())

    def parse(self, words: tuple[int, ...], t: float) -> Readings:
        def var(name: str) -> tuple[int, ...]:
            offset, size = self.link.variables[name]
            return words[offset - self.start : offset - self.start + size]

        ground = var("prox.ground.delta")
        return Readings(
            t=t,
            prox=var("prox.horizontal"),
            ground=(ground[0], ground[1]),
            speeds=(var("motor.left.speed")[0], var("motor.right.speed")[0]),
            buttons=tuple(
                var(f"button.{b}")[0] for b in ("backward", "left", "center", "forward", "right")
            ),
            leds=words[self.led_words + LED_WORDS - self.start :][:LED_WORDS],
        )

    def stop_now(self) -> None:
        self.drive.stop()
        self.send()


async def connect(
    robot_id: str,
    link: str,
    *,
    node: int | None = None,
    spec: dict[str, Any] | None = None,
    tick_period: float = 0.05,
    timeout: float = 2.0,
    locator: Callable[[ThymioOdometry], RadioLocator | None] | None = None,
) -> ThymioHardware:
    """Connect to the Thymio at ``link`` (``tcp:HOST:PORT`` or a serial device) as ``robot_id``.

    ``node``: the Aseba node id (None: the first that answers; several Thymios on one link, as
    behind ``asebaswitch``, need it). ``spec``: ``pose`` ([x, y, heading], where odometry
    starts) and ``calibration`` (:meth:`Calibration.of`). ``tick_period``: seconds between
    control ticks; ``timeout``: seconds an answer may take before the robot counts as lost.
    ``locator`` makes the radio's locator from the odometry (the default: the odometry itself;
    see :mod:`robots.thymio` for a lab's tracking system). HardwareLost if the robot is not
    there or is not a Thymio II.
    """
    spec = spec or {}
    cal = Calibration.of(spec.get("calibration", {}))
    start: Pose = tuple(float(v) for v in spec.get("pose", (0.0, 0.0, 0.0)))  # type: ignore[assignment]
    conn = await AsebaLink.open(Address.parse(link), node, timeout)
    try:
        conn.require(SENSED + DRIVEN)
        drive, leds = ThymioDrive(cal), Leds()
        thymio = _Thymio(conn, cal, drive, leds, timeout)
        conn.load(led_program(conn, thymio.led_words))
        conn.farewell = tuple(
            aseba.set_variables(HOST, conn.node, conn.variables[name][0], (0,)) for name in DRIVEN
        )
        thymio.stop_now()
        first = await thymio.exchange()
    except BaseException:
        await conn.aclose()
        raise
    odometry = ThymioOdometry(cal, first, start)
    leds.readings = first
    prox, ground, buttons = Proximity(cal, first), Ground(cal, first), Buttons(cal, first)

    def took(readings: Readings) -> None:
        odometry.advance(readings)
        for device in (odometry, prox, ground, buttons):
            device.readings = readings
        leds.readings = readings

    clock = ThymioClock(tick_period, first, thymio.exchange, took, thymio.stop_now)
    watch = asyncio.get_running_loop().create_task(conn.wait_lost())
    watch.add_done_callback(lambda t: clock.lose(t.result()) if not t.cancelled() else None)
    radio = (locator or OdometryLocator)(odometry)
    return ThymioHardware(
        id=robot_id,
        clock=clock,
        drive=drive,
        odometry=odometry,
        sonar=prox,
        led=leds,
        radio=radio,
        ground=ground,
        buttons=buttons,
        leds=leds,
        calibration=cal,
        link=link,
        aseba=conn,
    )


class OdometryLocator:
    """The radio's locator from dead reckoning: where the robot believes it is. It drifts, so
    range-limited broadcast drifts with it (see docs/thymio.md for a lab's tracking system)."""

    def __init__(self, odometry: ThymioOdometry) -> None:
        self._odometry = odometry

    def position(self) -> Pose | None:
        """The odometry's pose."""
        return self._odometry.pose()
