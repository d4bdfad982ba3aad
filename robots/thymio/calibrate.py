"""``python -m robots.thymio.calibrate``: measure a simulated Thymio's calibration.

Prints the figures ``robots.thymio.Calibration`` holds, measured against the world's geometry
(the only ground truth the Aseba protocol leaves: the Playground does not tell poses):

* **proximity curve**: robots placed facing a wall at known distances (centre to wall) read
  ``prox.horizontal[2]``; the farthest robot whose reading is saturated (robots placed
  nearer are pushed back to contact) gives the centre-to-sensor distance, and so each
  reading's distance from the sensor;
* **speed per unit**: a robot drives across two dark stripes 0.30 m apart on the floor; the
  time between its ground sensors' two crossings gives m/s at each motor target;
* **wheel base**: a robot spins in place on the edge of a dark half-plane; its ground sensors
  cross the edge twice per turn, which times a turn, and so the turn rate at known wheel speeds.

Needs ``asebaplayground`` (Debian package ``aseba``); takes about 30 s.
"""

from __future__ import annotations

import asyncio
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

from mover.testing import free_port

from ._link import Address, AsebaLink
from .playground import (
    PlaygroundRobot,
    ground_png,
    playground_command,
    start_playground,
    stop_playground,
    world_xml,
)

#: Centre-to-wall distances (metres) of the proximity robots.
PROX_DISTANCES = tuple(round(0.070 + 0.005 * i, 3) for i in range(6)) + tuple(
    round(0.10 + 0.02 * i, 3) for i in range(11)
)
WALL_Y = 1.6  # the wall's near face
STRIPES = (0.40, 0.70)  # x of the two dark stripes (2 cm wide) the runner crosses
RUN_TARGETS = (100, 200, 400)  # motor targets of the runners, one each
SPIN_TARGET = 300
SPIN = (1.5, 0.8)  # where the spinner stands: on the edge of the dark half-plane y > 0.8


async def _read(link: AsebaLink, name: str) -> tuple[int, ...]:
    offset, size = link.variables[name]
    return await link.read(offset, size, 2.0)


async def proximity(ports: list[int]) -> list[tuple[float, float]]:
    """(centre-to-wall distance, mean raw prox.horizontal[2]) per proximity robot."""
    out = []
    for d, port in zip(PROX_DISTANCES, ports, strict=True):
        link = await AsebaLink.open(Address(host="127.0.0.1", port=port), None, 5.0)
        raws = [(await _read(link, "prox.horizontal"))[2] for _ in range(10)]
        await link.aclose()
        out.append((d, statistics.fmean(raws)))
    return out


async def _crossings(
    link: AsebaLink, duration: float, targets: tuple[int, int]
) -> list[tuple[float, bool]]:
    """Times (host clock) at which the left ground sensor changed between dark and bright."""
    link.write("motor.left.target", targets[:1])
    link.write("motor.right.target", targets[1:])
    seen: list[tuple[float, bool]] = []
    last: bool | None = None
    end = time.monotonic() + duration
    while time.monotonic() < end:
        dark = (await _read(link, "prox.ground.delta"))[0] < 500
        if dark != last:
            seen.append((time.monotonic(), dark))
            last = dark
        await asyncio.sleep(0.002)
    link.write("motor.left.target", (0,))
    link.write("motor.right.target", (0,))
    return seen[1:]  # the first is the start, not a crossing


async def speed(port: int, target: int) -> float:
    """m/s per motor unit at ``target``: time between the two stripes' leading edges."""
    link = await AsebaLink.open(Address(host="127.0.0.1", port=port), None, 5.0)
    try:
        marks = [t for t, dark in await _crossings(link, 0.70 / (target * 0.00033), (target,) * 2)
                 if dark]  # fmt: skip
    finally:
        await link.aclose()
    if len(marks) < 2:
        raise RuntimeError(f"the runner crossed {len(marks)} stripes at target {target}")
    return (STRIPES[1] - STRIPES[0]) / (marks[1] - marks[0]) / target


async def turn_rate(port: int, target: int) -> float:
    """rad/s of a spin at wheel targets (-target, +target): two edge crossings per turn."""
    link = await AsebaLink.open(Address(host="127.0.0.1", port=port), None, 5.0)
    try:
        times = [t for t, _ in await _crossings(link, 8.0, (-target, target))]
    finally:
        await link.aclose()
    if len(times) < 4:
        raise RuntimeError(f"the spinner crossed the edge {len(times)} times")
    turns = [b - a for a, b in zip(times, times[2:], strict=False)]
    return 2 * math.pi / statistics.fmean(turns)


async def main() -> int:
    """Measure and print (see the module docstring)."""
    if playground_command() is None:
        print("calibrate: asebaplayground is not installed (Debian package: aseba)")
        return 1
    with tempfile.TemporaryDirectory(prefix="thymio-cal-") as tmp:
        folder = Path(tmp)
        prox_robots = [
            PlaygroundRobot(f"p{i}", 0.1 + 0.15 * i, WALL_Y - d, math.pi / 2, free_port())
            for i, d in enumerate(PROX_DISTANCES)
        ]
        runners = {
            t: PlaygroundRobot(f"run{t}", 0.10, 0.12 + 0.12 * i, 0.0, free_port())
            for i, t in enumerate(RUN_TARGETS)
        }
        spinner = PlaygroundRobot("spinner", *SPIN, 0.0, free_port())
        robots = [*prox_robots, *runners.values(), spinner]
        stripes = [(x - 0.01, 0.0, x + 0.01, 0.5) for x in STRIPES]
        (folder / "ground.png").write_bytes(
            ground_png((3.0, 1.62), [*stripes, (1.0, SPIN[1], 2.0, 1.1)])
        )
        world = folder / "cal.playground"
        world.write_text(
            world_xml(
                robots,
                size=(3.0, 1.62),
                walls=[(1.5, WALL_Y + 0.01, 3.0, 0.02)],
                ground="ground.png",
            )
        )
        proc = await start_playground(world, [r.port for r in robots])
        try:
            await asyncio.sleep(1.0)  # let the bodies settle
            table = await proximity([r.port for r in prox_robots])
            measured = await asyncio.gather(
                turn_rate(spinner.port, SPIN_TARGET),
                *(speed(r.port, t) for t, r in runners.items()),
            )
            rate, speeds = measured[0], dict(zip(RUN_TARGETS, measured[1:], strict=True))
            unit = statistics.fmean(speeds.values())
        finally:
            await stop_playground(proc)
    top = max(raw for _, raw in table)
    contact = max(d for d, raw in table if raw >= top - 5)  # the farthest saturated reading
    print("proximity (prox.horizontal[2]), robot facing a wall:")
    print("  centre-to-wall m   from-sensor m   raw")
    for d, raw in table:
        print(f"  {d:14.3f}   {d - contact:13.3f}   {raw:5.0f}")
    print(f"contact (readings stop growing) at centre-to-wall {contact:.3f} m")
    for t, s in speeds.items():
        print(f"speed at target {t}: {s * t:.4f} m/s = {s:.3e} m/s per unit")
    print(f"speed_per_unit = {unit:.4e} m/s (max_speed at 500: {unit * 500:.3f} m/s)")
    base = 2 * SPIN_TARGET * unit / rate
    print(f"spin at ±{SPIN_TARGET}: {rate:.3f} rad/s -> wheel_base = {base:.4f} m")
    return 0


if __name__ == "__main__":
    sys.exit(asyncio.run(main()))
