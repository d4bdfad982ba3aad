"""Run a module with this process's wall clock off by some seconds (a robot without NTP).

``python -m tests.helpers.skewed SECONDS MODULE ARGS...``: ``time.time()`` (and so every
timestamp the process writes) reads SECONDS more than the real clock, then MODULE runs as
``python -m MODULE ARGS...`` would run it.
"""

from __future__ import annotations

import runpy
import sys
import time


def main() -> None:
    offset = float(sys.argv[1])
    real = time.time
    time.time = lambda: real() + offset
    module = sys.argv[2]
    sys.argv = [module, *sys.argv[3:]]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
