"""Simonin et al. (INRIA RR-6171, 2007): the setups of sections 4.5, 5.3, 5.4 and the figures
the paper reports, which the report prints beside ours."""

from __future__ import annotations

from dataclasses import dataclass

# The paper's figures: Table 1 (mean, std), Table 2 (measured, projected), Table 3 (iterations).
PAPER_T1 = {5: (19200, 10071), 10: (8697, 4282), 20: (4114, 1890), 40: (2263, 1134),
            80: (1070, 448), 160: (574, 420)}  # fmt: skip
PAPER_T2 = {1: (1790.4, 1790.4), 2: (871.5, 895.2), 3: (582.9, 596.8), 4: (438.7, 447.6),
            5: (356.1, 358.1), 6: (302.0, 298.4), 7: (266.5, 255.8), 8: (236.2, 223.8)}  # fmt: skip
PAPER_T3 = {12: 155.5, 25: 345.0, 50: 805.0, 100: 2290.0, 200: 7844.0}
#: Section 5.5: "the difference ... decreases (from 73% to 52% to 37%)" as the size grows.
PAPER_FIG9_GAPS = (73, 52, 37)
#: Agents in Setup 3 (Table 3, Figure 9).
SETUP3_AGENTS = 50


@dataclass(frozen=True)
class Setup:
    """One of the paper's setups (sections 4.5, 5.3, 5.4)."""

    size: int
    density: float
    n_resources: int
    quantity: int
    q_max: int = 100


SETUP1 = Setup(40, 0.30, 20, 1000)
SETUP2 = Setup(20, 0.05, 2, 1000)


def setup3(size: int) -> Setup:
    """Setup 3 at one environment size."""
    return Setup(size, 0.05, 20, 2000)
