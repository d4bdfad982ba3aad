"""The Thymio backend over a fake Aseba node: the serial path (a pty, as a USB cable or a
wireless dongle is), ``node=`` among several nodes on one stream (as behind ``asebaswitch``),
and the ``locator=`` hook for a lab's tracking system."""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import os
import shutil
import tty
from collections.abc import AsyncIterator

import pytest

from mover._config import free_port
from robots import Robot
from robots.hal import HardwareLost, Pose, RadioLocator
from robots.library import MissingDevice, needs
from robots.thymio import OdometryLocator, ThymioHardware, connect
from robots.thymio._devices import ThymioOdometry
from robots.thymio._hardware import SENSED
from robots.thymio._link import Address, list_nodes
from robots.thymio.nodes import main as nodes_main

from .fake_node import LED_WORDS, NODE, TABLE, VARIABLES, FakeBus, FakeNode, offset


@contextlib.asynccontextmanager
async def _pty(*fakes: FakeNode) -> AsyncIterator[tuple[str, int]]:
    """A pty served by ``fakes`` on its master side: (the device path, the master fd)."""
    master, slave = os.openpty()
    tty.setraw(slave)  # as the link sets it (asebaswitch opens it too)
    os.set_blocking(master, False)
    serving = asyncio.get_running_loop().create_task(FakeBus(*fakes).serve_fd(master))
    try:
        yield os.ttyname(slave), master
    finally:
        serving.cancel()
        await asyncio.gather(serving, return_exceptions=True)
        for fd in (master, slave):
            with contextlib.suppress(OSError):  # (closed by the test: the cable pulled)
                os.close(fd)


async def test_the_serial_path_over_a_pty_drives_reads_and_loses_the_robot() -> None:
    """The whole HAL through a serial device: the handshake, the LED program loaded, motor
    targets and lights set, buttons read; the cable pulled is HardwareLost in one line."""
    fake = FakeNode()
    async with _pty(fake) as (device, master):
        hw = await connect("t1", device, tick_period=0.01, timeout=1.0)
        assert isinstance(hw, ThymioHardware) and hw.link == device
        assert fake.bytecode[:2] == (3, 0xFFFE - 1)  # on the "buttons" event (the 2nd)
        fake.set("button.center", 1)
        fake.set("prox.horizontal", 0, 0, 4000, 0, 0, 0, 0)
        hw.drive.set_velocity(0.1, 0.0)
        hw.leds.show("green")
        await hw.clock.tick()
        await hw.clock.tick()
        target = round(0.1 / hw.calibration.speed_per_unit)
        assert (fake.get("motor.left.target"), fake.get("motor.right.target")) == (target,) * 2
        assert tuple(fake.table[LED_WORDS : LED_WORDS + 3]) == (0, 32, 0)
        assert hw.leds.shown() == ((0, 32, 0), (0,) * 8)  # (the fake applies at once)
        assert hw.buttons.pressed() == {"center"}
        assert hw.sonar is not None and hw.sonar.ranges()[2] < hw.sonar.max_range
        assert hw.odometry.pose()[0] > 0  # the speeds read back are integrated
        os.close(master)  # the cable pulled
        with pytest.raises(HardwareLost) as lost:
            await _tick_until_lost(hw)
        assert device in str(lost.value) and "\n" not in str(lost.value)


async def _tick_until_lost(hw: ThymioHardware) -> None:
    async with asyncio.timeout(3):
        while True:
            await hw.clock.tick()


async def test_a_serial_path_with_no_device_is_one_line() -> None:
    with pytest.raises(HardwareLost, match=r"^no Thymio at /dev/no-such-tty: No such file"):
        await connect("t1", "/dev/no-such-tty", timeout=1.0)


def test_the_nodes_tool_says_what_is_wrong_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert nodes_main(["/dev/no-such-tty"]) == 1
    said = capsys.readouterr().err
    assert said == "error: no Thymio at /dev/no-such-tty: No such file or directory\n"
    assert nodes_main(["ttyACM0"]) == 1
    assert "expected tcp:HOST:PORT or a serial device path" in capsys.readouterr().err


async def test_node_picks_one_robot_among_several_on_one_link(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Two nodes behind one TCP port: the nodes tool lists both; ``node=`` connects to its
    own; its commands reach only it, its readings come only from it."""
    first, second = FakeNode(NODE), FakeNode(NODE + 1, name="thymio-B")
    second.set("button.left", 1)
    server = await asyncio.start_server(FakeBus(first, second).serve_stream, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    async with server:
        here = Address(host="127.0.0.1", port=port)
        assert await list_nodes(here, 0.3) == {NODE: "thymio-II", NODE + 1: "thymio-B"}
        assert await asyncio.to_thread(nodes_main, [f"tcp:127.0.0.1:{port}", "--wait", "0.3"]) == 0
        assert capsys.readouterr().out == f"node {NODE}: thymio-II\nnode {NODE + 1}: thymio-B\n"
        hw = await connect("t2", f"tcp:127.0.0.1:{port}", node=NODE + 1, tick_period=0.01)
        hw.drive.set_velocity(0.05, 0.0)
        await hw.clock.tick()
        await hw.clock.tick()
        assert hw.buttons.pressed() == {"left"}
        assert second.get("motor.left.target") > 0 and first.get("motor.left.target") == 0
        assert not first.bytecode and second.bytecode  # the LED program went to t2's only
        server.close()


@pytest.mark.processes
@pytest.mark.skipif(
    shutil.which("asebaswitch") is None,
    reason="asebaswitch is not installed (Debian package: aseba)",
)
async def test_two_robots_on_one_serial_device_through_asebaswitch() -> None:
    """What docs/thymio.md says for several robots behind one wireless dongle, with aseba's own
    switch: ``asebaswitch -p PORT ser:device=DEVICE`` (here a pty with two nodes on it, as a
    dongle paired with two robots), then one link per robot, ``tcp:…:PORT`` with its
    ``node``: each drives its own robot and reads its own sensors."""
    first, second = FakeNode(NODE), FakeNode(NODE + 1)
    second.set("button.left", 1)
    port = free_port()
    async with _pty(first, second) as (device, _):
        switch = await asyncio.create_subprocess_exec(
            "asebaswitch", "-p", str(port), f"ser:device={device}",
            stdout=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.DEVNULL,
        )  # fmt: skip
        try:
            link = f"tcp:127.0.0.1:{port}"
            found = await _listed(Address(port=port, host="127.0.0.1"))
            assert found == {NODE: "thymio-II", NODE + 1: "thymio-II"}
            one = await _connect_soon("t1", link, NODE)
            two = await _connect_soon("t2", link, NODE + 1)
            one.drive.set_velocity(0.1, 0.0)
            two.drive.set_velocity(0.0, -1.0)
            for _ in range(3):
                await asyncio.gather(one.clock.tick(), two.clock.tick())
            forward = round(0.1 / one.calibration.speed_per_unit)
            assert (first.get("motor.left.target"), first.get("motor.right.target")) == (
                forward, forward)  # fmt: skip
            left, right = second.get("motor.left.target"), second.get("motor.right.target")
            assert left == -right > 0  # turning clockwise in place
            assert not one.buttons.pressed() and two.buttons.pressed() == {"left"}
        finally:
            switch.terminate()
            await switch.wait()


async def _listed(address: Address) -> dict[int, str]:
    """The nodes on ``address`` once the switch listens and has them."""
    async with asyncio.timeout(10):
        while True:
            with contextlib.suppress(HardwareLost):
                found = await list_nodes(address, 0.5)
                if found:
                    return found
            await asyncio.sleep(0.2)


async def _connect_soon(name: str, link: str, node: int) -> ThymioHardware:
    """Connect once the switch listens (it takes a moment to start)."""
    async with asyncio.timeout(10):
        while True:
            try:
                return await connect(name, link, node=node, tick_period=0.02)
            except HardwareLost:
                await asyncio.sleep(0.2)


class _Tracker:
    """A lab's tracking system for one robot: its latest pose, or None while it is not seen."""

    def __init__(self, odometry: ThymioOdometry) -> None:
        self.odometry = odometry
        self.seen: Pose | None = None

    def position(self) -> Pose | None:
        return self.seen


async def test_the_locator_hook_gives_the_radio_a_tracker() -> None:
    """By default the radio's position is the odometry's, from the spec's pose; ``locator=``
    replaces it with what the function makes of the odometry."""
    fake = FakeNode()
    server = await asyncio.start_server(FakeBus(fake).serve_stream, "127.0.0.1", 0)
    link = f"tcp:127.0.0.1:{server.sockets[0].getsockname()[1]}"
    async with server:
        plain = await connect("t1", link, spec={"pose": [0.5, 0.2, 1.0]})
        assert isinstance(plain.radio, OdometryLocator)
        assert plain.radio.position() == plain.odometry.pose() == (0.5, 0.2, 1.0)
        tracked = await connect("t1", link, locator=_Tracker)
        radio = tracked.radio
        assert isinstance(radio, _Tracker) and isinstance(radio, RadioLocator)
        assert radio.odometry is tracked.odometry and radio.position() is None  # not seen yet
        radio.seen = (1.0, 2.0, 0.0)
        assert radio.position() == (1.0, 2.0, 0.0)
        server.close()


def test_the_fake_node_has_what_the_backend_reads() -> None:
    names = {n for n, _ in VARIABLES}
    assert set(SENSED) <= names and TABLE == LED_WORDS + 22
    assert offset("button.backward") == 1


async def test_a_program_that_needs_a_camera_fails_at_start_on_a_thymio() -> None:
    """``@needs("camera")``: on a Thymio the program fails before its first line, in one line
    naming the device and what the robot has; a program that needs what it has runs."""
    ran: list[str] = []

    @needs("ground", "camera")
    async def look(robot: Robot[ThymioHardware], team: object, far: float = 1.0) -> float:
        ran.append(robot.id)
        return far

    @needs("ground", "sonar")
    async def feel(robot: Robot[ThymioHardware], team: object) -> str:
        return robot.id

    assert look.needs == ("ground", "camera")  # type: ignore[attr-defined]
    assert list(inspect.signature(look).parameters) == ["robot", "team", "far"]
    fake = FakeNode()
    server = await asyncio.start_server(FakeBus(fake).serve_stream, "127.0.0.1", 0)
    async with server:
        hw = await connect("t1", f"tcp:127.0.0.1:{server.sockets[0].getsockname()[1]}")
        robot = Robot("t1", hw)
        with pytest.raises(MissingDevice) as missing:
            await look(robot, None, far=2.0)
        said = str(missing.value)
        assert said.startswith("program look needs a camera; the robot's hardware")
        assert "(ThymioHardware) has none (it has: clock, drive, odometry, sonar" in said
        assert "\n" not in said and not ran and isinstance(missing.value, HardwareLost)
        assert await feel(robot, None) == "t1"
        server.close()
    with pytest.raises(MissingDevice, match="program feel needs a ground; this member has no"):
        await feel(Robot("w", None), None)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="not a device's name"):
        needs("a camera")
