"""Journal benchmark: how fast the file grows, and what retention holds it to.

Run with the project's Python (``.venv/bin/python benchmarks/journal.py``). It writes, through
the real ``Journal`` (writer thread, WAL, ``synchronous=FULL``) on a temporary file, simulated
daemon hours on a simulated clock (written as fast as the disk takes them): every second one
``Telemetry`` entry for ten channels (1 Hz summaries of 100 Hz readings, made by the real
``TelemetryDownsampler``), and a busy robot's decisions — an observation change every 5 s, a
diagnosis every 30 s, a plan with two actions (started + finished entries) every 2 minutes.
It reports the cost of one ``record()`` call (what the asyncio loop pays), the bytes per
hour of telemetry alone and of the whole mix (after a WAL checkpoint, so the numbers are the
database file), and the file size after six hours with a one-hour telemetry retention. It
prints a Markdown table for ``benchmarks/RESULTS.md``; the sizes depend on SQLite's page
layout, not on the machine; the ``record()`` cost does.
"""

import math
import os
import sqlite3
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout before benchmarks/

from host.journal import (
    ActionRecord,
    ActionState,
    DiagnosisRecord,
    Journal,
    Observation,
    PlanRecord,
    PlanStep,
    Retention,
    TelemetryDownsampler,
)

T0 = 1_800_000_000.0
HOUR = 3600


def _size(path: Path) -> int:
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    conn.close()
    return os.path.getsize(path) + (os.path.getsize(f"{path}-wal")
                                    if os.path.exists(f"{path}-wal") else 0)


def simulate(path: Path, hours: float, *, decisions: bool,
             retention: Retention | None = None) -> int:
    """Write ``hours`` of simulated activity; returns the file size in bytes."""
    ds = TelemetryDownsampler(1.0)
    with Journal(path, retention=retention) as journal:
        for k in range(int(hours * HOUR * 100) + 1):  # 100 Hz readings
            t = k / 100
            currents = {ch: 500 + 300 * math.sin(t / 7 + ch) + (k * 7919 % 13) for ch in range(10)}
            summary = ds.add(t, currents)
            if summary is not None:
                journal.record(summary, wall=T0 + t, mono=t)
            if not decisions or k % 100:
                continue
            s = k // 100
            if s % 5 == 0:
                journal.record(Observation(f"ok(node_{s % 17})", s % 10 == 0, "topic"),
                               wall=T0 + t, mono=t)
            if s % 30 == 0:
                journal.record(DiagnosisRecord.of([["hokuyo_node"], ["hokuyo", "hokuyo_node"]],
                                                  trigger="observation", elapsed_s=0.004),
                               wall=T0 + t, mono=t)
            if s % 120 == 0:
                steps = (PlanStep("power_up", ("hokuyo",)),
                         PlanStep("start_node", ("hokuyo_node",)))
                journal.record(PlanRecord(f"p{s}", steps, ("hokuyo_node",)), wall=T0 + t, mono=t)
                for i, st in enumerate(steps):
                    for state in (ActionState.STARTED, ActionState.SUCCEEDED):
                        journal.record(ActionRecord(f"a{s}.{i}", st.action, st.args, state, T0 + t,
                                                    None if state == ActionState.STARTED
                                                    else T0 + t + 1.2, f"p{s}"),
                                       wall=T0 + t, mono=t)
        journal.flush_blocking()
    return _size(path)


def record_cost(path: Path, n: int = 20000) -> tuple[float, float]:
    """Median and 99th percentile of one ``record()`` call, in microseconds (the loop's cost)."""
    costs = []
    with Journal(path) as journal:
        for i in range(n):
            obs = Observation(f"ok(node_{i % 17})", i % 2 == 0, "topic")
            t = time.perf_counter_ns()
            journal.record(obs, wall=T0 + i, mono=float(i))
            costs.append(time.perf_counter_ns() - t)
        journal.flush_blocking()
    costs.sort()
    return costs[n // 2] / 1000, costs[n * 99 // 100] / 1000


def main() -> None:
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        t0 = time.perf_counter()
        tele = simulate(tmp / "tele.sqlite", 1, decisions=False)
        mix = simulate(tmp / "mix.sqlite", 1, decisions=True)
        kept = simulate(tmp / "kept.sqlite", 6, decisions=True,
                        retention=Retention(telemetry_max_age_s=HOUR, prune_every=60))
        elapsed = time.perf_counter() - t0
        median_us, p99_us = record_cost(tmp / "cost.sqlite")
        with Journal(tmp / "kept.sqlite") as j:
            counts = j.reader.counts()
    print("| measure | value |")
    print("|---|---|")
    print(f"| telemetry only (10 channels, 1 Hz summaries), per hour | {tele / 1e6:.2f} MB |")
    print(f"| per telemetry entry | {tele / HOUR:.0f} B |")
    print(f"| telemetry + decisions (obs/5 s, diagnosis/30 s, plan/2 min), per hour "
          f"| {mix / 1e6:.2f} MB |")
    print(f"| 6 h of the same with 1 h telemetry retention | {kept / 1e6:.2f} MB "
          f"({counts['telemetry']} telemetry, {counts['observation']} observations, "
          f"{counts['action']} actions kept) |")
    print(f"| one record() call on the daemon's loop, median / p99 | {median_us:.1f} / "
          f"{p99_us:.1f} us |")
    print(f"\n(simulated 8 hours in {elapsed:.1f} s)")


if __name__ == "__main__":
    if "--help" in sys.argv or "-h" in sys.argv:
        print("usage: python benchmarks/journal.py  (or python -m benchmarks.journal)\n")
        print(__doc__)
        sys.exit(0)
    main()
