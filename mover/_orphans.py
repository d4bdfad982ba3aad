"""Children that die with their parent: a command run through a few lines of Python that ask
Linux for a signal when the process that started it dies (``PR_SET_PDEATHSIG``, kept across
``exec``), and that do not start at all if it died already. Elsewhere the command runs as is.

This is a wrapper, not a ``preexec_fn``: running Python between ``fork`` and ``exec`` in a
process with other threads (zenoh's) can deadlock the child.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Sequence

_GUARD = (
    "import ctypes,os,sys\n"
    "try: ctypes.CDLL(None).prctl(1, int(sys.argv[2]))\n"  # PR_SET_PDEATHSIG
    "except (OSError, AttributeError): pass\n"
    "if os.getppid() != int(sys.argv[1]): sys.exit(70)\n"
    "os.execv(sys.argv[3], sys.argv[3:])\n"
)


def guarded(argv: Sequence[str], sig: int = signal.SIGKILL) -> list[str]:
    """``argv`` (its first item a path to a program) so that it gets ``sig`` when this process
    dies. Start the result as this process's child."""
    if sys.platform != "linux":
        return list(argv)
    return [sys.executable, "-I", "-S", "-c", _GUARD, str(os.getpid()), str(int(sig)), *argv]
