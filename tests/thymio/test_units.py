"""The Thymio backend without a robot: the Aseba wire format pinned by real bytes, the
calibration, the LED program's bytecode, the devices and the real-time clock over a fake link."""

from __future__ import annotations

import asyncio
import math
from types import SimpleNamespace
from typing import Any

import pytest

from robots.hal import Clock, Drive, HardwareLost, Led, Odometry, Sonar
from robots.thymio import Calibration, Leds, require
from robots.thymio import _aseba as aseba
from robots.thymio._clock import ThymioClock
from robots.thymio._devices import Proximity, Readings, ThymioDrive, ThymioOdometry, colour_of
from robots.thymio._hardware import led_program
from robots.thymio._link import Address

# What the Playground (aseba 1.6.99) answered: NODE_PRESENT from node 1, protocol 5, and the
# head of its DESCRIPTION ("thymio-II", 30 named variables, 17 local events, 52 natives).
NODE_PRESENT = b"\x02\x00\x01\x00\x0c\x90\x05\x00"
DESCRIPTION = b"\x18\x00\x01\x00\x00\x90\tthymio-II\x05\x00\xfe\x05 \x00J\x02\x1e\x00\x11\x004\x00"
NAMED = b"\x06\x00\x01\x00\x01\x90\x01\x00\x03_id"


def test_split_takes_whole_messages_and_keeps_a_partial_one() -> None:
    buffer = bytearray(NODE_PRESENT + DESCRIPTION + NAMED[:5])
    msgs = aseba.split(buffer)
    assert [m.type for m in msgs] == [aseba.NODE_PRESENT, aseba.DESCRIPTION]
    assert bytes(buffer) == NAMED[:5]
    buffer += NAMED[5:]
    (named,) = aseba.split(buffer)
    assert aseba.decode_named_variable(named.payload) == ("_id", 1) and not buffer


def test_decode_the_playgrounds_answers() -> None:
    present, head = aseba.split(bytearray(NODE_PRESENT + DESCRIPTION))
    assert present.source == 1 and aseba.decode_present(present.payload) == 5
    assert aseba.decode_description(head.payload) == aseba.Description("thymio-II", 5, 30, 17, 52)


def test_host_messages_encode_as_aseba_does() -> None:
    assert aseba.list_nodes(1).encode() == b"\x02\x00\x01\x00\x11\xa0\x05\x00"
    assert aseba.get_node_description(1, 1).encode() == b"\x04\x00\x01\x00\x10\xa0\x01\x00\x05\x00"
    assert aseba.get_variables(1, 1, 37, 24).encode() == (
        b"\x06\x00\x01\x00\x0b\xa0\x01\x00\x25\x00\x18\x00"
    )
    assert aseba.set_variables(1, 1, 57, (-200,)).encode() == (
        b"\x06\x00\x01\x00\x0c\xa0\x01\x00\x39\x00\x38\xff"
    )
    start, values = aseba.decode_variables(b"\x39\x00\x38\xff\xc8\x00")
    assert (start, values) == (57, (-200, 200))


def test_a_stream_that_is_not_aseba_is_refused() -> None:
    with pytest.raises(ValueError, match="not an Aseba stream"):
        aseba.split(bytearray(b"GET / HTTP/1.1\r\n"))
    with pytest.raises(ValueError, match="int16"):
        aseba.set_variables(1, 1, 0, (40000,))


def test_addresses() -> None:
    assert Address.parse("tcp:localhost:33333") == Address(host="localhost", port=33333)
    assert Address.parse("tcp:33334") == Address(host="127.0.0.1", port=33334)
    assert str(Address.parse("/dev/ttyACM0")) == "/dev/ttyACM0"
    for bad in ("tcp:host:x", "ttyACM0", "tcp:h:70000"):
        with pytest.raises(ValueError, match="expected"):
            Address.parse(bad)


def test_calibration_maps_velocity_to_targets_and_back() -> None:
    cal = Calibration()
    left, right = cal.targets(0.1, 0.0)
    assert left == right == round(0.1 / cal.speed_per_unit)
    v, w = cal.motion(*cal.targets(0.05, 1.0))
    assert v == pytest.approx(0.05, abs=1e-3) and w == pytest.approx(1.0, abs=0.01)
    # Too fast for a wheel: scaled whole, the turn radius kept.
    left, right = cal.targets(1.0, 2.0)
    assert max(abs(left), abs(right)) == cal.max_target
    assert cal.motion(left, right)[0] / cal.motion(left, right)[1] == pytest.approx(0.5, rel=0.01)


def test_the_proximity_curve_falls_with_distance_and_holds_at_its_ends() -> None:
    cal = Calibration()
    assert cal.distance(0) == cal.reach
    distances = [cal.distance(raw) for raw in range(0, 5000, 250)]
    assert distances == sorted(distances, reverse=True)
    assert cal.distance(10_000) == cal.prox[-1][1]


def test_calibration_from_a_spec_refuses_what_it_does_not_know() -> None:
    assert Calibration.of({"wheel_base": 0.095}).wheel_base == 0.095
    with pytest.raises(ValueError, match="no key wheelbase"):
        Calibration.of({"wheelbase": 0.1})
    with pytest.raises(ValueError, match="raw increasing"):
        Calibration.of({"prox": [[100, 0.01], [50, 0.1]]})


def test_the_led_program_calls_the_natives_on_the_buttons_event() -> None:
    link: Any = SimpleNamespace(
        events=["button.backward", "button.left", "button.center", "button.forward",
                "button.right", "buttons", "prox"],
        natives=[f"n{i}" for i in range(34)] + ["leds.circle", "leds.top"],
    )  # fmt: skip
    code = led_program(link, 74)
    assert code[:3] == (3, 0xFFFE - 5, 3)
    top = code[3:7]
    assert top == (0x1000 | 76, 0x1000 | 75, 0x1000 | 74, 0xC000 | 35)
    circle = code[7:16]
    assert circle[0] == 0x1000 | 84 and circle[7] == 0x1000 | 77 and circle[8] == 0xC000 | 34
    copies = code[16:-1]  # load word 74+i, store it at 85+i: what was applied, for the host
    assert copies == tuple(w for i in range(11) for w in (0x3000 | (74 + i), 0x4000 | (85 + i)))
    assert code[-1] == 0


def _readings(
    t: float, prox: tuple[int, ...] = (0,) * 7, speeds: tuple[int, int] = (0, 0)
) -> Readings:
    return Readings(t=t, prox=prox, ground=(900, 900), speeds=speeds, buttons=(0, 0, 1, 0, 0))


def test_devices_are_the_hals() -> None:
    cal = Calibration()
    first = _readings(0.0, prox=(0, 0, 4000, 0, 0, 0, 0))
    prox = Proximity(cal, first)
    assert isinstance(prox, Sonar) and isinstance(ThymioDrive(cal), Drive)
    assert isinstance(Leds(), Led) and isinstance(ThymioOdometry(cal, first, (0, 0, 0)), Odometry)
    ranges = prox.ranges()
    assert ranges[2] < prox.max_range and ranges[0] == prox.max_range


def test_odometry_integrates_the_measured_speeds() -> None:
    cal = Calibration()
    odo = ThymioOdometry(cal, _readings(0.0), (1.0, 2.0, 0.0))
    straight = round(0.1 / cal.speed_per_unit)
    for i in range(1, 11):  # 1 s straight at 0.1 m/s
        new = _readings(0.1 * i, speeds=(straight, straight))
        odo.advance(new)
        odo.readings = new
    x, y, th = odo.pose()
    assert (x, y, th) == pytest.approx((1.1, 2.0, 0.0), abs=1e-3)
    spin = cal.targets(0.0, math.pi / 2)
    for i in range(11, 21):  # 1 s turning at π/2 rad/s in place
        new = _readings(0.1 * i, speeds=spin)
        odo.advance(new)
        odo.readings = new
    assert odo.pose()[2] == pytest.approx(math.pi / 2, abs=0.01)
    assert odo.pose()[:2] == pytest.approx((1.1, 2.0), abs=1e-3)


def test_a_status_lights_a_colour_of_its_own() -> None:
    assert colour_of("red") == (32, 0, 0) and colour_of("#0000ff") == (0, 0, 32)
    assert colour_of("mark:t1") == colour_of("mark:t1") != colour_of("mark:t2")
    leds = Leds()
    leds.show("green")
    leds.circle((32,) * 8)
    assert leds.words() == (0, 32, 0, *(32,) * 8)


def test_require_names_the_missing_device() -> None:
    hw = SimpleNamespace(camera=None, ground=object())
    require(hw, "ground")
    from dataclasses import dataclass

    @dataclass
    class Hw:
        id: str
        ground: object
        camera: object = None

    with pytest.raises(HardwareLost, match=r"needs a camera.*it has: ground"):
        require(Hw("t", object()), "ground", "camera")


class _FakeThymio:
    """An exchange that answers with readings a period apart, and can lose the robot."""

    def __init__(self) -> None:
        self.sent = 0
        self.stopped = 0
        self.lost: HardwareLost | None = None

    async def exchange(self) -> Readings:
        await asyncio.sleep(0)
        if self.lost is not None:
            raise self.lost
        self.sent += 1
        return _readings(1000.0 + self.sent * 0.01)


async def test_the_clock_ticks_at_its_rate_holds_and_loses() -> None:
    fake = _FakeThymio()
    clock = ThymioClock(0.01, _readings(1000.0), fake.exchange, lambda r: None, lambda: None)
    assert isinstance(clock, Clock)
    loop = asyncio.get_running_loop()
    begun = loop.time()
    for _ in range(5):
        await clock.tick()
    assert loop.time() - begun >= 0.035 and clock.now() == pytest.approx(1000.05)
    await clock.passed(1000.04)  # handed in on those readings already
    clock.hold(clock.now() - 0.001)
    held = asyncio.ensure_future(clock.tick())
    await asyncio.sleep(0.03)
    assert not held.done()
    clock.hold(None)
    await asyncio.wait_for(held, 1.0)
    async with clock.idling():
        with pytest.raises(RuntimeError, match="idle"):
            await clock.tick()
        await asyncio.sleep(0.03)
    assert fake.sent > 6  # the keeper polled while idle
    waiter = asyncio.ensure_future(clock.passed(math.inf))
    fake.lost = HardwareLost("gone")
    with pytest.raises(HardwareLost, match="gone"):
        await clock.tick()
    with pytest.raises(HardwareLost, match="gone"):
        await asyncio.wait_for(waiter, 1.0)


def test_the_wander_keeps_its_side_in_front_of_a_wall_and_drifts_in_the_open() -> None:
    import random

    from robots.thymio import PROX_ANGLES, ProxWander

    wander = ProxWander(random.Random(1), speed=0.1)
    wall = (0.1, 0.05, 0.03, 0.05, 0.1, 0.1, 0.1)  # straight ahead, the same on both sides
    turns = {wander.step(wall, PROX_ANGLES, 0.1)[1] for _ in range(20)}
    assert len(turns) == 1 and turns != {0.0}  # one side, kept: no dithering
    left = (0.02, 0.04, 0.1, 0.1, 0.1, 0.1, 0.1)
    fresh = ProxWander(random.Random(1))
    v, w = fresh.step(left, PROX_ANGLES, 0.1)
    assert w < 0 and v < 0.1  # away from the left, slower
    v, w = fresh.step((0.1,) * 7, PROX_ANGLES, 0.1)
    assert v == fresh.speed and abs(w) <= 0.8


async def test_a_handshake_asks_again_and_takes_the_late_answer() -> None:
    """The first question goes unanswered (a Playground just up): the answer to the second
    one is taken, not swallowed by what the first wait left behind."""
    from robots.thymio._link import AsebaLink

    asked = 0

    async def node(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        nonlocal asked
        buffer = bytearray()
        while chunk := await reader.read(100):
            buffer += chunk
            for msg in aseba.split(buffer):
                if msg.type == aseba.LIST_NODES:
                    asked += 1
                    if asked >= 3:
                        writer.write(NODE_PRESENT)
                elif msg.type == aseba.GET_NODE_DESCRIPTION:
                    head = b"\tthymio-II\x05\x00\xfe\x05 \x00J\x02\x01\x00\x00\x00\x00\x00"
                    writer.write(aseba.Message(aseba.DESCRIPTION, 1, head).encode() + NAMED)
        writer.close()

    server = await asyncio.start_server(node, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    async with server:
        link = await AsebaLink.open(Address(host="127.0.0.1", port=port), None, 5.0)
        assert asked >= 3 and link.variables == {"_id": (0, 1)} and link.name == "thymio-II"
        await link.aclose()
