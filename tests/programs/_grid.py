"""Starting a grid world process and grid robot processes for the distributed tests."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tests.helpers.procs import Cluster

WORLD = "gridworld"


async def start_world(c: Cluster, path: Path, *args: str) -> asyncio.subprocess.Process:
    """``mover gridworld FILE ARGS`` as a process; returns once it serves."""
    return await c.start("mover._cli", "gridworld", str(path), *args, ready="READY")


async def start_robots(
    c: Cluster,
    names: Sequence[str],
    specs: Sequence[dict[str, Any]] | None = None,
) -> list[asyncio.subprocess.Process]:
    """``mover robot --hardware grid`` processes, started together (the world may wait for
    all of them before the first round); return once every one has joined."""
    specs = specs or [{} for _ in names]
    return list(
        await asyncio.gather(
            *(
                c.start(
                    "robots",
                    "--name",
                    name,
                    "--hardware",
                    "grid",
                    "--world",
                    WORLD,
                    "--spec",
                    json.dumps(spec),
                    timeout=40.0,
                )
                for name, spec in zip(names, specs, strict=True)
            )
        )
    )


def write_grid(
    path: Path, obstacles: Any, base: tuple[int, int], resources: dict[tuple[int, int], int]
) -> Path:
    """Write a grid JSON file (``sim_hw.grid`` format)."""
    path.write_text(
        json.dumps(
            {
                "cells": obstacles.astype(int).tolist(),
                "base": list(base),
                "resources": [[r, c, q] for (r, c), q in resources.items()],
            }
        )
    )
    return path
