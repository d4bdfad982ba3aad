"""The collectives: ``distributed_or`` and ``distributed_and`` among the members of a run.

A member's side (:class:`TaskTeam`, ``_member``), the node's side that serves the steps it is
designated for and holds each step's decision (:class:`Collectives`, ``_designated``; its
parts ``_designated_or``, ``_designated_and`` and ``_questions`` decide the steps it serves), this
member's operations as the designated member asks about them (``_operations``), what a step is
(``_step``), the one owner of a step's tasks (``_group``), the run's clock (:class:`RunClock`,
``_clock``). The protocol, its costs and its wire: ``docs/collectives.md``.
"""

from ._clock import RunClock
from ._designated import RUN_LOST, Collectives
from ._member import TaskTeam
from ._reach import wait_reachable
from ._step import (
    POLICIES,
    SEED_LIMIT,
    Decision,
    OperationFailed,
    Outcome,
    Policy,
    StepMetrics,
    seed_of,
)

__all__ = [
    "POLICIES",
    "RUN_LOST",
    "SEED_LIMIT",
    "Collectives",
    "Decision",
    "OperationFailed",
    "Outcome",
    "Policy",
    "RunClock",
    "StepMetrics",
    "TaskTeam",
    "seed_of",
    "wait_reachable",
]
