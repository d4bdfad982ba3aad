"""``python -m experiments.maze ARGS``: the same as ``mover experiment maze ARGS``."""

import sys

from experiments.cli import main
from experiments.maze import register

sys.exit(main("maze", register))
