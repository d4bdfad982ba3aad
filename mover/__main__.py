"""``python -m mover``: the ``mover`` command."""

import sys

from mover.cli._main import main

if __name__ == "__main__":
    sys.exit(main())
