"""``python -m experiments.eyebot ARGS``: the same as ``mover experiment eyebot ARGS``."""

import sys

from experiments.cli import main
from experiments.eyebot import register

sys.exit(main("eyebot", register))
