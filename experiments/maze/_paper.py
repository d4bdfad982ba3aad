"""The maze paper's experiment (Linardakis et al., sections IV-V): its grid and its metrics.

The paper runs 30x30 mazes at obstacle probabilities 0.85 (corridors) and 0.15 (nearly open)
with 1 to 20 agents, and compares the methods on six metrics (section IV-C), combined into
the composite index of section V-B with equal weights.
"""

from __future__ import annotations

AGENT_COUNTS = (1, 2, 4, 6, 8, 10, 15, 20)
PROBABILITIES = (0.85, 0.15)
SIZE = 30
#: Metric key, label, whether larger is better (composite index, section V-B).
METRICS = (
    ("time_s", "exploration time (s, eq. 4)", False),
    ("rounds", "exploration rounds", False),
    ("cost", "exploration cost (cells moved, eq. 5)", False),
    ("efficiency", "exploration efficiency (eq. 6)", True),
    ("quality", "map quality (eq. 7)", True),
    ("comm_kB", "communication, msgpack bytes sent (kB)", False),
)
#: Reported beside the metrics, not ranked.
EXTRA = (
    ("comm_paper_kB", "communication, paper eq. 8 (kB)"),
    ("step_ms", "computation per agent step (ms)"),
)
