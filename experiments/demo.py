"""`mover demo`: search and rescue on real processes in the simulated world, end to end.

Starts the team of ``teams/search_and_rescue.toml`` with ``mover up``'s supervisor: a world
process (lock-step, recording) and one robot process per robot of the world file; runs a
program on them (default ``search_and_rescue``) once all are members; shows live progress, then
a report — winner, time per phase in simulated and wall seconds, messages per collective step,
how far each box moved — and a PNG of the trajectories. Everything talks over zenoh on
127.0.0.1 with a fresh team key; every process's log is kept in the output folder; nothing is
left running.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import sys
import time
from dataclasses import dataclass, field, replace
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from mover import PROGRESS_TOPIC
from mover._up import (
    ProcessExited,
    Stopped,
    Supervisor,
    TeamFileError,
    TeamPlan,
    UpError,
    load_team,
)
from mover.cli import UsageError, add_command, json_object, positive
from sim_hw import STATE_TOPIC, WorldFileError, load_world
from sim_hw._process import control_delay

from ._common import writable_dir

ROOT = Path(__file__).resolve().parents[1]
TEAM_FILE = ROOT / "teams" / "search_and_rescue.toml"
DEFAULT_WORLD = ROOT / "worlds" / "search_and_rescue.toml"


def register(sub: Any) -> None:
    """Add ``mover demo``."""
    p = add_command(
        sub,
        "demo",
        run,
        "search and rescue with robot processes in a simulated world",
        __doc__.split("\n\n")[0],
    )
    p.add_argument("--program", default="search_and_rescue", help="the program to run")
    p.add_argument("--world", default=str(DEFAULT_WORLD), help="the world file")
    p.add_argument("--args", default="{}", metavar="JSON", help="the program's arguments")
    p.add_argument("--out", default="out/demo", help="directory for the logs, recording and PNG")
    p.add_argument(
        "--seed",
        type=int,
        default=1,
        help="the run seed (the world's sensor noise and the program's choices derive from it)",
    )
    p.add_argument("--timeout", type=positive, default=120.0, help="wall seconds before giving up")
    p.add_argument(
        "--control-delay",
        type=control_delay,
        default=0,
        metavar="K",
        help="the world applies a command K ticks after it was handed in (default 0; what a "
        "team across hosts runs with, see docs/reproducible-runs.md)",
    )


@dataclass(frozen=True)
class DemoSettings:
    """A demo run: the program and its arguments, the world file and its robots, the goal
    (its first target, for the report), where to write, the run seed, the time allowed, the
    world's control delay in ticks."""

    program: str
    world: Path
    robots: tuple[str, ...]
    program_args: dict[str, Any] = field(default_factory=dict)
    goal: tuple[float, float] | None = None
    out: Path = Path("out/demo")
    seed: int = 1
    timeout: float = 120.0
    control_delay: int = 0


def settings(args: argparse.Namespace) -> DemoSettings:
    """The settings the command line asks for, the world file read; raises
    :class:`~mover.cli.UsageError` naming what is wrong."""
    world = Path(args.world)
    try:
        spec = load_world(world)
    except WorldFileError as exc:
        raise UsageError(f"world file {exc}") from None
    if not spec.robots:
        raise UsageError(f"world file {world}: no [[robots]] with an id")
    if not 0 <= args.seed < 2**63:
        raise UsageError(f"--seed must be from 0 to 2**63-1, got {args.seed}")
    program_args = json_object(args.args, "--args")
    installed = sorted(ep.name for ep in entry_points(group="mover.programs"))
    if args.program not in installed:  # the members run what is installed here
        raise UsageError(
            f"--program {args.program!r} is not installed (installed: {', '.join(installed)})"
        )
    out = writable_dir(Path(args.out), "--out")
    goals = [m.center for m in spec.markers if m.kind == "target"]
    return DemoSettings(
        program=args.program,
        world=world,
        robots=tuple(spec.robots),
        program_args=program_args,
        goal=(float(goals[0][0]), float(goals[0][1])) if goals else None,
        out=out,
        seed=args.seed,
        timeout=args.timeout,
        control_delay=args.control_delay,
    )


def team_plan(s: DemoSettings, source: Path = TEAM_FILE) -> TeamPlan:
    """The demo's team file with the command line's world, robots, program and seed."""
    try:
        plan = load_team(source)
    except TeamFileError as exc:
        raise UsageError(f"team file {exc}") from None
    if plan.world is None or plan.program is None or not plan.members:
        raise UsageError(f"team file {source}: needs a [world], [[robots]] and a [program]")
    group = plan.members[0]
    robots = tuple(replace(group, name=name) for name in s.robots)  # the world file's bodies
    return replace(
        plan,
        seed=s.seed,
        world=replace(plan.world, file=s.world, expect=len(robots), control_delay=s.control_delay),
        members=robots,
        program=replace(plan.program, name=s.program, args=s.program_args, members=()),
    )


def run(args: argparse.Namespace) -> int:
    """Run the demo the command line asks for."""
    s = settings(args)
    return asyncio.run(demo(s, team_plan(s)))


async def demo(s: DemoSettings, plan: TeamPlan) -> int:
    """Start the team, run the program, report; 0 if every member ended without error."""
    assert plan.world is not None and plan.program is not None
    robots = plan.robots()
    wall0 = time.monotonic()
    seen = _Seen(wall0)
    sup = Supervisor(plan, out=s.out, echo=False)
    print(
        f"mover demo: {s.program} with {', '.join(robots)} in {s.world.name} "
        f"(team key is fresh; zenoh on 127.0.0.1:{sup.port}; seed {s.seed}; logs in {s.out})",
        flush=True,
    )
    try:
        async with sup:
            states = sup.node.subscribe(STATE_TOPIC)
            progress = sup.node.subscribe(f"{PROGRESS_TOPIC}/{plan.program.run}")
            await sup.wait_ready()
            print(
                f"[{time.monotonic() - wall0:5.1f}s] world and {len(robots)} robot processes up",
                flush=True,
            )
            watcher = asyncio.create_task(seen.watch(progress, states))
            try:
                outcomes = await sup.guard(
                    asyncio.wait_for(
                        sup.launch(s.program, robots, s.program_args, run=plan.program.run),
                        s.timeout,
                    )
                )
            finally:
                await asyncio.sleep(0.2)
                watcher.cancel()
                await asyncio.wait([watcher])  # ended; its cancellation is not ours to raise
    except TimeoutError:
        print(f"mover demo: no result within {s.timeout} s", file=sys.stderr)
        return 1
    except (UpError, ProcessExited) as exc:  # the team did not come up, or a process exited
        print(f"mover demo: {exc}", file=sys.stderr)
        return 1
    except Stopped:
        print("mover demo: stopped before the report", file=sys.stderr)
        return 130
    wall = time.monotonic() - wall0
    ok = _report(outcomes, seen.phases, seen.boxes, wall, s.goal)
    recording, png = s.out / f"{plan.world.name}.jsonl", s.out / "trajectories.png"
    replay = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "mover._cli", "replay", str(recording), "--out", str(png),
        stdout=asyncio.subprocess.DEVNULL,
    )  # fmt: skip
    if await replay.wait() == 0:
        print(f"trajectories: {png}")
    return 0 if ok else 1


@dataclass
class _Seen:
    """What the demo watches while the program runs: the members' progress reports (printed,
    and the first report of each phase timed) and the world's snapshots (the boxes' tracks)."""

    wall0: float
    phases: dict[str, list[float]] = field(default_factory=dict)  # phase -> [wall s, sim s]
    boxes: dict[str, list[list[float]]] = field(default_factory=dict)
    sim: float = 0.0

    async def watch(self, progress: Any, states: Any) -> None:
        """Follow both subscriptions until cancelled."""
        async with asyncio.TaskGroup() as tg:
            tg.create_task(self._track_states(states))
            await self._track_progress(progress)

    async def _track_states(self, states: Any) -> None:
        async for m in states:
            self.sim = float(m.data.get("t", 0.0))
            for bid, pose in m.data.get("boxes", {}).items():
                self.boxes.setdefault(bid, []).append(list(pose[:2]))

    async def _track_progress(self, progress: Any) -> None:
        async for m in progress:
            data = dict(m.data)
            member, phase = data.pop("member", "?"), data.pop("phase", "?")
            # the member's own simulated time, when its report carries one; else the world's
            # last snapshot here (which races the report by a snapshot or so)
            sim = data.pop("t", None)
            sim = float(sim) if isinstance(sim, int | float) else self.sim
            now = time.monotonic() - self.wall0
            first = self.phases.setdefault(phase, [now, sim])
            first[1] = min(first[1], sim)  # the earliest member, whichever report came first
            extra = " ".join(f"{k}={_fmt(v)}" for k, v in data.items())
            line = f"[{now:5.1f}s | sim {sim:6.1f}s] {member}: {phase} {extra}"
            print(line.rstrip(), flush=True)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.2f}"
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def _report(
    outcomes: dict[str, dict[str, Any]],
    phases: dict[str, list[float]],
    boxes: dict[str, list[list[float]]],
    wall: float,
    goal: tuple[float, float] | None,
) -> bool:
    print("\n== report ==")
    ok = True
    for member, outcome in outcomes.items():
        if "error" in outcome:
            ok = False
            print(f"{member}: FAILED {outcome['error']}")
        else:
            print(f"{member}: {json.dumps(outcome.get('result'), default=str)}")
    if phases:
        print("phases (first report; wall s, simulated s):")
        for phase, (w, s) in phases.items():
            print(f"  {phase:<12} wall {w:6.1f}  sim {s:6.1f}")
    steps: dict[int, list[Any]] = {}
    for outcome in outcomes.values():
        for st in outcome.get("steps", []):
            entry = steps.setdefault(st["step"], [st["kind"], 0])
            entry[1] += st["messages"]
    n = len(outcomes)
    for step, (kind, msgs) in sorted(steps.items()):
        # the designated-member costs of docs/collectives.md; an OR is decided in simulated time
        # here (a lock-step world): at most 4(n-1); other kinds: all-to-all, 2n(n-1)
        designated = {"or": 4 * (n - 1), "and": 2 * (n - 1), "begin": 2 * (n - 1)}
        designated["rejoin"] = 2 * (n - 1)
        bound = designated.get(kind, 2 * n * (n - 1))
        print(f"step {step} ({kind}): {msgs} messages for {n} members (bound {bound})")
    for bid, track in boxes.items():
        if len(track) >= 2:
            moved = math.dist(track[0], track[-1])
            line = f"box {bid!r} moved {moved:.2f} m: {_fmt(track[0])} -> {_fmt(track[-1])}"
            if goal is not None:
                gained = math.dist(track[0], goal) - math.dist(track[-1], goal)
                line += f"; {gained:.2f} m nearer the goal {_fmt(list(goal))}"
                line += f" (now {math.dist(track[-1], goal):.2f} m from it)"
            print(line)
    print(f"wall time {wall:.1f} s")
    return ok
