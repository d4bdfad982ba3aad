"""``python -m experiments.foraging ARGS``: the same as ``mover experiment foraging ARGS``."""

import sys

from experiments.cli import main
from experiments.foraging import register

sys.exit(main("foraging", register))
