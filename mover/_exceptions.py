"""The errors mover raises, as one tree.

::

    MoverError
    ├── WireError                  a frame that does not decode, or a value that cannot be sent
    │   └── PayloadTooLarge        over the node's size limit
    ├── CallError                  a remote call failed (has .robot and .procedure)
    │   ├── Answered               the callee answered, with an error: asking again is futile
    │   │   ├── RemoteError        the procedure raised; .remote_type and .message say what
    │   │   ├── UnknownProcedure   the robot exports no procedure of that name
    │   │   ├── BadArguments       the arguments do not fit the procedure's signature or hints
    │   │   └── Refused            the callee refused the request (authentication, replay)
    │   └── NotDelivered           no answer came: the call may be asked again
    │       ├── CallTimeout        no answer within the timeout (also a TimeoutError)
    │       ├── RobotLost          the callee left the team (died, hung, cut off) mid-call
    │       └── UnknownRobot       no team member of that name answers
    ├── MemberLost                 a member of a collective step left before it finished
    ├── NameTaken                  a live member already holds the name a node would take
    ├── ConfigError                a team or transport setting is wrong (also a ValueError)
    │   ├── Unreachable            no router or peer answered at the endpoints within a bound
    │   └── FileError              a file is wrong: .source, .line, .where (the key), .problem
    │       ├── TeamFileError      a team file (mover up)
    │       ├── WorldFileError     a continuous world file, or a robot's settings (sim_hw)
    │       ├── GridFileError      a grid file (sim_hw.grid)
    │       └── MazeFileError      a maze file (sim_hw.grid)
    └── NodeClosed                 the node was closed while the operation was pending

Errors cross processes as data (type name and message), never as pickled objects.

Beside the tree, :class:`ExpectedFault` marks the faults of what mover runs (a robot's hardware
that went away, ``robots.hal.HardwareLost``) that a program run reports in one line, as it does
every MoverError, rather than as a bug with its traceback.
"""

from __future__ import annotations


class MoverError(Exception):
    """Base of every error mover raises."""


class WireError(MoverError):
    """A frame that does not decode, or a value that cannot be encoded."""


class PayloadTooLarge(WireError):
    """An envelope is over the size limit."""


class NodeClosed(MoverError):
    """The node was closed while an operation was pending."""


class CallError(MoverError):
    """A remote call failed; ``robot`` and ``procedure`` say which."""

    def __init__(self, message: str, *, robot: str = "", procedure: str = "") -> None:
        super().__init__(message)
        self.robot = robot
        self.procedure = procedure


class Answered(CallError):
    """The callee answered the call with an error: asking again would get the same answer."""


class NotDelivered(CallError):
    """No answer came (timeout, callee lost or unknown): the call may be asked again."""


class RemoteError(Answered):
    """The remote procedure raised ``remote_type`` with ``message``."""

    def __init__(self, remote_type: str, message: str, *, robot: str, procedure: str) -> None:
        super().__init__(
            f"{procedure!r} on {robot!r} raised {remote_type}: {message}",
            robot=robot,
            procedure=procedure,
        )
        self.remote_type = remote_type
        self.message = message


class UnknownProcedure(Answered):
    """The robot does not export a procedure of that name."""


class BadArguments(Answered):
    """The arguments do not fit the procedure's signature or type hints."""


class CallTimeout(NotDelivered, TimeoutError):
    """No answer came within the call's timeout."""


class RobotLost(NotDelivered):
    """The callee left the team (process died, hung or was cut off) before answering."""


class UnknownRobot(NotDelivered):
    """No member of the team by that name answers."""


class Refused(Answered):
    """The callee refused the request: bad signature, other team, stale or replayed."""


class MemberLost(MoverError):
    """A member of a collective step left the team before the step finished."""

    def __init__(self, message: str, *, members: frozenset[str] = frozenset()) -> None:
        super().__init__(message)
        self.members = members


class ConfigError(MoverError, ValueError):
    """A team or transport setting (from the environment, a flag or a file) is wrong."""


class Unreachable(ConfigError):
    """A node could not reach any of the endpoints it connects to (its router, its peers)
    within the bound it was given: the endpoints are wrong, or the network or the router is
    down. Raised by ``Node.open`` for a tool (a CLI verb); a member process waits instead."""


class FileError(ConfigError):
    """A file (or a table of settings) is wrong: ``source``, ``line``, ``where`` and ``problem``.

    Raised by every reader of files (:mod:`mover._tables`), with one wording:
    ``teams/a.toml:12: robots[1].count: must be from 1 to 200, got 1000``. ``line`` is None
    where the format keeps no lines (a JSON key) and ``where`` is "" for the file as a whole.
    Fix the file; the message says where and what was expected.
    """

    def __init__(self, source: str, where: str, problem: str, *, line: int | None = None) -> None:
        self.source, self.where, self.problem, self.line = source, where, problem, line
        at = source if line is None else f"{source}:{line}"
        super().__init__(f"{at}: {where}: {problem}" if where else f"{at}: {problem}")


class NameTaken(MoverError):
    """A live member of the team already holds the name; ``holder`` says who (pid, host)."""

    def __init__(self, message: str, *, holder: object = None) -> None:
        super().__init__(message)
        self.holder = holder


# Errors a callee may report by name; anything else arrives as RemoteError.
CALL_ERRORS: dict[str, type[CallError]] = {
    cls.__name__: cls for cls in (UnknownProcedure, BadArguments, Refused)
}


class ExpectedFault(Exception):
    """Base of the faults that are expected in a robot's life (its hardware went away), not bugs.

    A program run that fails with one is logged in one line, without a traceback, as one that
    fails with a :class:`MoverError`. Subclass it (``class HardwareLost(ExpectedFault)``) rather
    than mark a class otherwise: ``except ExpectedFault`` then catches every such fault.
    """
