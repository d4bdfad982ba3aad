"""`mover experiment foraging`: Simonin et al.'s foraging tables, re-measured in-process.

Runs many seeded trials of c-marking agents (Algorithm 4) and of the ant-model baseline on the
grid world, and prints the paper's Tables 1–3 and the Figure 9 comparison beside ours:

* Table 1 — Setup 1: 40×40, 30 % obstacles, 20 resources × 1000 units, q_max 100, 5…160 agents;
* Table 2 — Setup 2: 20×20, 5 %, 2 resources × 1000; 1…8 agents; projected V_ref/n vs measured;
* Table 3 — Setup 3: 12×12…200×200, 5 %, 20 resources × 2000, 50 agents; ratio R;
* Figure 9 ("ants") — c-marking vs ants in Setup 3;
* "model" — how consistent the three tables are: T = a·D + b·TB fitted to each (D: time for
  exploring agents to find every source; TB: the transport lower bound), the paper's and ours.

The c-marking reading is the default of ``CMarkingAgent`` unless asked otherwise:
``--trail-colours per-trail`` (one colour per trail), ``--climb-any`` (the letter's climb),
``--colour-on-move``, ``--forget-at-base``, ``--literal``. ``--agent-seeds K`` runs each
environment with K agent seeds, the standard error then taken over environments.

Time is the paper's (section 5.1): iterations until every resource location is exhausted, one
iteration being every agent acting once. The base is in the centre and every agent starts there.
Every trial's seed derives from ``--seed``: the environment of run k is the same for every agent
count (common random numbers), the agents' generator differs. By default each row runs until the
standard error is at most 5 % of its mean (at least ``--min-runs`` runs, at most ``--max-runs``);
``--runs N`` fixes the count instead.
"""

from ._cli import register, run, settings
from ._paper import (
    PAPER_FIG9_GAPS,
    PAPER_T1,
    PAPER_T2,
    PAPER_T3,
    SETUP1,
    SETUP2,
    Setup,
    setup3,
)
from ._report import table1, table2, table3
from ._settings import TARGET_SE, ForagingSettings
from ._trial import (
    Row,
    Trial,
    environment,
    measure,
    run_trial,
    table1_rows,
    table2_rows,
    table3_rows,
)

__all__ = [
    "PAPER_FIG9_GAPS",
    "PAPER_T1",
    "PAPER_T2",
    "PAPER_T3",
    "SETUP1",
    "SETUP2",
    "TARGET_SE",
    "ForagingSettings",
    "Row",
    "Setup",
    "Trial",
    "environment",
    "measure",
    "register",
    "run",
    "run_trial",
    "settings",
    "setup3",
    "table1",
    "table1_rows",
    "table2",
    "table2_rows",
    "table3",
    "table3_rows",
]
