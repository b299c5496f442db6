"""Ctrl-C reaches the process, not the SAT solver it happens to be in.

PySAT's C solvers, when called from the main thread, replace the process's SIGINT handler for
the length of each call with one that aborts the call and raises ``pysolvers.error("Caught
keyboard interrupt")`` (``pysat._utils.MainThread.check`` decides). dxboard solves on its
main thread, inside its asyncio loop, where SIGINT is a request to stop that the loop's
signal handler serves: a Ctrl-C or ``kill -INT`` landing in a solve never reached it, and the
error it became was caught where a failed diagnosis is logged (the recorder of a suite run
on a busy machine ignored its SIGINT for good that way). Importing this module tells PySAT
that no call is made from the main thread, so it leaves SIGINT alone: the signal is served
by the process's own handler once the call returns (a diagnosis is bounded by its deadline).
Every module of dxboard that solves imports it through ``host.diagnosis.satctx``.
"""

from __future__ import annotations

from pysat._utils import MainThread  # type: ignore[import-untyped]


def _never_main() -> bool:
    return False


MainThread.check = staticmethod(_never_main)
