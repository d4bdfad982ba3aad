"""`mover experiment maze`: CU-LVP and its baselines on seeded mazes, in-process.

Linardakis et al., sections IV-V. Each trial builds a maze (section IV-A), puts N agents on its
first N start cells, and runs rounds until the union of the agents' maps knows every inner cell
the agents can see (an observer measures it; the agents never see it). Per round every agent
senses, broadcasts what changed (msgpack, delivered to the agents within range and decoded
from the bytes), hears, relays what it heard to the same agents (``--exchanges``), decides,
and moves, in agent order (a move into an occupied cell fails). Metrics (section IV-C):
rounds, exploration cost (4-connected moves made), efficiency M / cost, map quality
(M - errors) / P, communication (bytes actually sent, relays included, beside the paper's
equation (8)), and computation time per agent step (equation (4) uses its mean times rounds).
"""

from ._cli import register, run, settings
from ._paper import AGENT_COUNTS, EXTRA, METRICS, PROBABILITIES
from ._report import composite, composite_text, tables
from ._settings import MazeSettings
from ._trial import run_trial, trials

__all__ = [
    "AGENT_COUNTS",
    "EXTRA",
    "METRICS",
    "PROBABILITIES",
    "MazeSettings",
    "composite",
    "composite_text",
    "register",
    "run",
    "run_trial",
    "settings",
    "tables",
    "trials",
]
