"""A trivial random-walk robot: the driver of the tests and the benchmark (not a behaviour).

It shows the shape of a robot process on the HAL — read sensors, decide, set the drive, wait a
tick — and records the robot's true pose each tick (through the radio locator, which real
behaviours must not use) so that runs can be compared.

Run as a process: ``python -m sim_hw.continuous._walker ROBOT --seed N --ticks T [--out FILE]``;
it joins the world process over mover (``MOVER_CONNECT`` etc. from the environment).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys

import numpy as np

from robots.hal import Hardware, RadioLocator


async def random_walk(hw: Hardware, rng: np.random.Generator, ticks: int) -> list[list[float]]:
    """Wander for ``ticks`` ticks, turning away from close sonar echoes; returns true poses."""
    track: list[list[float]] = []
    omega = 0.0
    # the first readings (at join) may not show robots that joined later: decide nothing on them
    hw.drive.stop()
    await hw.clock.tick()
    for _ in range(ticks):
        ranges = hw.sonar.ranges() if hw.sonar else ()
        ahead = min(
            (r for i, r in enumerate(ranges) if i in (0, 1, len(ranges) - 1)),
            default=hw.sonar.max_range if hw.sonar else 9.0,
        )
        if ahead < 0.4 or (hw.bumper and hw.bumper.pressed()):
            hw.drive.set_velocity(0.0, 1.5)
        else:
            if rng.random() < 0.1:
                omega = float(rng.uniform(-1.0, 1.0))
            hw.drive.set_velocity(0.3, omega)
        await hw.clock.tick()
        loc = hw.radio.position() if hw.radio else None
        if loc is not None:
            track.append(list(loc))
    hw.drive.stop()
    return track


class _Radio:
    """A locator for the node, which exists before the hardware it reads."""

    source: RadioLocator | None = None

    def position(self) -> tuple[float, float, float] | None:
        return self.source.position() if self.source else None


async def _main(args: argparse.Namespace) -> list[list[float]]:
    from mover import Node, NodeConfig, TeamCredentials

    from ._hardware import remote

    team = TeamCredentials.from_env()
    radio = _Radio()  # the node's locator; it reads the HAL's radio once there is one
    async with Node(
        args.robot, team=team, kind="robot", config=NodeConfig.from_env(), locator=radio
    ) as node:
        hw = await remote(
            node,
            args.robot,
            json.loads(args.spec) if args.spec else None,
            call_timeout=args.timeout,
        )
        radio.source = hw.radio
        print("READY", flush=True)
        track = await random_walk(hw, np.random.default_rng(args.seed), args.ticks)
        await node.call("world", "leave", args.robot, timeout=args.timeout)
    return track


def main(argv: list[str] | None = None) -> int:
    """Parse arguments and run one walker process."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--ticks", type=int, default=100)
    parser.add_argument("--spec", default="", help="robot settings as JSON (world-file units)")
    parser.add_argument("--timeout", type=float, default=30.0)
    parser.add_argument("--out", default="")
    args = parser.parse_args(argv)
    track = asyncio.run(_main(args))
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            json.dump(track, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
