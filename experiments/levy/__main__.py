"""``python -m experiments.levy ARGS``: the same as ``mover experiment levy ARGS``."""

import sys

from experiments.cli import main
from experiments.levy import register

sys.exit(main("levy", register))
