"""Child processes that die with the daemon, even when it is killed with SIGKILL.

Everything dxboard starts (the emulated board, the robot's nodes) is started with
``preexec_fn=die_with_parent``: in the child, between fork and exec, Linux's
``prctl(PR_SET_PDEATHSIG, SIGKILL)`` asks the kernel to kill the child when the thread that
started it ends — which, for the daemon's event-loop thread, is when the daemon ends, however
it ends (issue 25, item 3: ``kill -9`` of the daemon left 9 node processes running with PPID 1
for good). The setting survives ``exec``. A child whose parent died before the ``prctl`` took
effect (the race the man page warns of) sees a changed parent pid and kills itself.

The function is resolved in the parent (``ctypes.CDLL`` must not load a library in a forked
child of a threaded process); on other systems ``die_with_parent`` does nothing and a clean
stop is the only way the children end.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from collections.abc import Callable

PR_SET_PDEATHSIG = 1


def _prctl() -> Callable[..., int] | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        fn: Callable[..., int] = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    return fn


_PRCTL = _prctl()


def lifeline(sig: int = signal.SIGKILL) -> Callable[[], None]:
    """A ``preexec_fn`` that ties the child to the process that calls this now."""
    parent = os.getpid()

    def preexec() -> None:
        if _PRCTL is not None:
            _PRCTL(PR_SET_PDEATHSIG, int(sig))
            if os.getppid() != parent:  # the daemon died before the line was tied
                os.kill(os.getpid(), sig)

    return preexec
