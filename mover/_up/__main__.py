"""``python -m mover._up TEAM.toml``: ``mover up`` without the ``mover`` command's frame."""

from __future__ import annotations

import argparse
import sys

from ..cli import UsageError, add_log_arguments, setup_logging
from . import DESCRIPTION, add_arguments, run


def main() -> int:
    """``mover up`` as its own command."""
    p = argparse.ArgumentParser(prog="python -m mover._up", description=DESCRIPTION)
    add_arguments(p)
    add_log_arguments(p)
    args = p.parse_args()
    try:
        setup_logging(args)
        return run(args)
    except UsageError as exc:
        print(f"mover up: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
