"""The library of robot procedures for MOVER's programs (Jennings et al., section 4.3).

Each procedure runs on one robot over its HAL (``robot.hw``) and stops the motors in a
``finally`` (a cancelled procedure leaves the robot still); each decision rule is a plain
function or small class of readings → command, testable without a world.

* search and recognition — :func:`search` (random walk, section 4.1), :func:`movable` (the push
  test), :func:`sees` (camera recognition), :func:`recognition` (by name), :class:`Found`,
  :class:`Wander`; a search limited to a region — :data:`Region`, :class:`Rect`;
* navigation — :func:`goto_object`, :func:`goto_point`, :func:`steer`, :func:`detour`,
  :func:`station`;
* manipulation — :func:`pusher`, :func:`steerer`, :class:`Path`, :func:`stations`,
  :func:`pusher_command`, :func:`steerer_command`, :func:`object_pose`;
* Lévy search (Sutantyo et al.) — :class:`LevyWalker` (eq. 10, Fig. 4), :func:`walker` and
  :data:`METHODS` (FL, L, L+P; :data:`WALKS` with their parts), :func:`levy_search`,
  :func:`repulsion` (eq. 9), :func:`mantegna` (eq. 11-12), :class:`LevySteps`, :class:`FixedSteps`,
  :func:`viswanathan_mu` (eq. 4-5), :func:`stable_alpha`, :func:`mean_flights` (eq. 3);
* training (section 5) — :func:`snapshot`;
* what a program needs of the hardware — :func:`needs` (declared, checked as it starts),
  :func:`require`, :class:`MissingDevice`.
"""

from robots.hal import MARK, MARKED

from ._geometry import Rect, Region
from ._goto import (
    approach,
    detour,
    follow,
    follow_command,
    goto_object,
    goto_point,
    sidestep,
    station,
    steer,
    turn_to,
)
from ._levy import (
    METHODS,
    WALKS,
    LevyCommand,
    LevyParams,
    LevySense,
    LevyWalker,
    Neighbour,
    hal_sense,
    levy_search,
    levy_sense,
    repulsion,
    walker,
)
from ._levy_steps import (
    FixedSteps,
    LevySteps,
    mantegna,
    mean_flights,
    stable_alpha,
    viswanathan_mu,
)
from ._manipulate import (
    Path,
    align,
    object_pose,
    pusher,
    pusher_command,
    sighting_of,
    stations,
    steerer,
    steerer_command,
)
from ._needs import MissingDevice, needs, require
from ._search import (
    Found,
    Predicate,
    Wander,
    kind_ahead,
    locate,
    movable,
    moved,
    recognition,
    search,
    sees,
    teammate_ahead,
)
from ._snapshot import snapshot

__all__ = [
    "MARK",
    "MARKED",
    "METHODS",
    "WALKS",
    "FixedSteps",
    "Found",
    "LevyCommand",
    "LevyParams",
    "LevySense",
    "LevySteps",
    "LevyWalker",
    "MissingDevice",
    "Neighbour",
    "Path",
    "Predicate",
    "Rect",
    "Region",
    "Wander",
    "align",
    "approach",
    "detour",
    "follow",
    "follow_command",
    "goto_object",
    "goto_point",
    "hal_sense",
    "kind_ahead",
    "levy_search",
    "levy_sense",
    "locate",
    "mantegna",
    "mean_flights",
    "movable",
    "moved",
    "needs",
    "object_pose",
    "pusher",
    "pusher_command",
    "recognition",
    "repulsion",
    "require",
    "search",
    "sees",
    "sidestep",
    "sighting_of",
    "snapshot",
    "stable_alpha",
    "station",
    "stations",
    "steer",
    "steerer",
    "steerer_command",
    "teammate_ahead",
    "turn_to",
    "viswanathan_mu",
    "walker",
]
