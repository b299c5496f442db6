"""A SIGINT that lands while dxboard's SAT solver runs reaches the process's own handler.

PySAT's solvers, called from the main thread, take SIGINT over for each call and turn it
into an exception of that call; dxboard's loop logs a failed diagnosis and goes on, so the
stop was lost (a recorder of a suite on a busy machine never stopped). The program below
does what the daemon and the recorder do: its loop's SIGINT handler asks it to stop, it
solves on the main thread inside the loop (a pigeonhole formula, about 0.1-1 s a call, so the
signal lands in a call), and a failed solve is logged, not fatal. It must stop, cleanly.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PROGRAM = r"""
import asyncio, signal, sys
import host.diagnosis.satctx  # what every solving module of dxboard imports
from pysat.examples.genhard import PHP
from pysat.solvers import Solver

async def main():
    stop = asyncio.Event()
    asyncio.get_running_loop().add_signal_handler(signal.SIGINT, stop.set)
    solved = 0
    while not stop.is_set():
        try:
            with Solver(name="g3", bootstrap_with=PHP(8).clauses) as s:
                print("solving", flush=True)
                s.solve()
            solved += 1
        except Exception as exc:  # as the loop's inbox does: logged, not fatal
            print("failed:", exc, file=sys.stderr, flush=True)
        await asyncio.sleep(0)
    print("stopped", flush=True)

asyncio.run(main())
"""


def test_a_sigint_during_a_solve_stops_the_loop() -> None:
    proc = subprocess.Popen([sys.executable, "-c", PROGRAM], cwd=ROOT, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert proc.stdout is not None
        first = proc.stdout.readline()  # a call begins now: the signal lands in it
        assert first.startswith("solving"), proc.stderr.read() if proc.stderr else ""
        proc.send_signal(signal.SIGINT)
        t0 = time.monotonic()
        out, err = proc.communicate(timeout=120)  # a deadline for the lost signal, no measure
        assert proc.returncode == 0, err
        assert out.splitlines()[-1] == "stopped", (out[-500:], err, time.monotonic() - t0)
        assert "Caught keyboard interrupt" not in err and "failed" not in err, err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
