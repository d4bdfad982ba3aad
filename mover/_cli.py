"""The old home of the ``mover`` command's frame, now :mod:`mover.cli` (``mover.cli._main``).

Kept so that ``python -m mover._cli VERB`` (how ``mover up`` and scripts start processes) and
``from mover._cli import main, UsageError`` go on working; new code uses ``python -m mover``.
"""

from __future__ import annotations

import sys

from .cli import UsageError
from .cli._main import build_parser, main

__all__ = ["UsageError", "build_parser", "main"]

if __name__ == "__main__":  # python -m mover._cli: the package's function, not __main__'s copy
    sys.exit(main())
