"""The main of the test robot processes (``python -m tests.…_robot NAME``), written once.

A test robot is ``mover robot``'s process (``robots.process.run_robot``; team and zenoh settings
from the MOVER_* environment) hosting the test's own programs; it prints ``READY`` once its
hardware is up, which is what ``Cluster.start`` waits for.
"""

from __future__ import annotations

import asyncio
import logging
import sys
from collections.abc import Callable, Mapping
from typing import Any

from mover import NodeConfig, TeamCredentials
from robots.process import run_robot


def run_test_robot(programs: Mapping[str, Callable[..., Any]], **options: Any) -> None:
    """Run the robot process named by the first argument, hosting ``programs``, until killed;
    ``options`` go to ``run_robot`` (its hardware and the hardware's options)."""
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    asyncio.run(
        run_robot(
            sys.argv[1],
            team=TeamCredentials.from_env(),
            config=NodeConfig.from_env(),
            programs=programs,
            ready=lambda: print("READY", flush=True),
            **options,
        )
    )
