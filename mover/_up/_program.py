"""The program of a team file, run by ``mover up`` once the team is ready: its progress and
outcomes as lines of ``mover up``'s stream."""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from typing import Any

from .._exceptions import MoverError
from .._programs import PROGRESS_TOPIC
from ._supervisor import Supervisor, _line


async def run_program(sup: Supervisor) -> bool:
    """Start the file's program on ``sup``'s team, print its progress and outcomes; True if
    every member ended without error."""
    p = sup.plan.program
    assert p is not None
    members = list(p.members) or sup.plan.robots()
    progress = sup.node.subscribe(f"{PROGRESS_TOPIC}/{p.run}")
    t0 = time.monotonic()

    async def show() -> None:
        async for m in progress:
            data = dict(m.data) if isinstance(m.data, dict) else {"data": m.data}
            member, phase = data.pop("member", m.sender), data.pop("phase", "?")
            extra = " ".join(f"{k}={_short(v)}" for k, v in data.items())
            _line(f"[{p.run}] {time.monotonic() - t0:6.1f}s {member}: {phase} {extra}".rstrip())

    shower = asyncio.create_task(show())
    _line(f"[{p.run}] {p.name} on {', '.join(members)} (program seed {sup.seeds.program})")
    try:
        outcomes = await sup.launch(p.name, members, p.args, run=p.run)
    except MoverError as exc:  # refused: an unknown program, bad arguments, a busy member
        _line(f"[{p.run}] not started: {type(exc).__name__}: {exc}")
        return False
    finally:
        await asyncio.sleep(0.1)  # the last progress reports
        shower.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await shower
        progress.close()
    ok = True
    for member, outcome in outcomes.items():
        if "error" in outcome:
            ok = False
            _line(f"[{p.run}] {member}: FAILED {outcome['error']}")
            for line in str(outcome.get("traceback") or "").rstrip().splitlines():
                _line(f"[{p.run}]   {line}")  # a bug in the program: where
        else:
            result = json.dumps(outcome.get("result"), default=str)
            _line(f"[{p.run}] {member}: {result}")
    took = time.monotonic() - t0
    _line(f"[{p.run}] {'ended' if ok else 'FAILED'} after {took:.1f} s")
    return ok


def _short(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.2f}"
    if isinstance(value, list) and value and all(isinstance(v, float) for v in value):
        return "[" + ", ".join(f"{v:.2f}" for v in value) + "]"
    return str(value)
