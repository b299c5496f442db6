"""The one fold of the event stream: what it costs per event, alone and with its views.

Run with the project's Python (``.venv/bin/python benchmarks/fold.py [--events N]``). It
builds a daemon-like stream: a 10-channel ``ChannelSample`` every event (the daemon's sample
task, a few a second, is most of the stream), with an observation, a diagnosis run and
record, and a repair step mixed in every few events, over 12 components and 40 observed
literals. It measures, in one run, the microseconds per event of ``EventFold.feed`` alone (the
baseline), of the fold with the page's projection (``PageProjection``: the whole ``Status``
rebuilt after every change), and of the fold with the page and ``/diagnostics``
(``Diagnostics.statuses()`` after every change, as the ROS 2 publisher does), and prints a
Markdown table with the ratios to the baseline for ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from host.events import (
    ActionRecord,
    ActionState,
    ChannelReading,
    ChannelSample,
    DiagnosisRecord,
    DiagnosisRun,
    Event,
    LinkChange,
    Observation,
    RunStarted,
    Stamped,
)
from host.fold import EventFold
from host.ros.status import Diagnostics
from host.web.fold import PageProjection
from host.web.status import MemoryStatusSource, Status

COMPONENTS = [f"device{i}" for i in range(12)]


def stream(n: int) -> list[Stamped]:
    """``n`` stamped events of a busy run (see the module's docstring)."""
    events: list[Event] = [RunStarted("bench", "bench", "tcp://127.0.0.1:7000"),
                           LinkChange(True, "connected", "accepted")]
    for i in range(n):
        events.append(ChannelSample(tuple(
            ChannelReading(c, f"device{c}", True, "on", 100.0 + (i * 7 + c) % 50)
            for c in range(10)), input_mv=24000))
        if i % 5 == 0:
            events.append(Observation(f"ok(/topic{i % 40})", i % 10 != 0, "bench"))
        if i % 10 == 0:
            events.append(DiagnosisRun(0.01, "observation"))
            bad = [[f"device{i % 12}"], [f"device{(i + 1) % 12}"]] if i % 20 == 0 else [[]]
            events.append(DiagnosisRecord.of(bad, probabilities=[0.6, 0.4][:len(bad)]))
        if i % 20 == 0:
            state = ActionState.STARTED if i % 40 == 0 else ActionState.SUCCEEDED
            events.append(ActionRecord(f"a{i // 40}", "power_cycle", (f"device{i % 12}",),
                                       state, float(i)))
    return [Stamped(1.8e9 + k * 0.1, 100.0 + k * 0.1, e) for k, e in enumerate(events)]


def per_event_us(events: list[Stamped], build: Callable[[], EventFold]) -> float:
    """Microseconds per event through a fresh fold with the views ``build`` attaches."""
    fold = build()
    t0 = time.perf_counter()
    for s in events:
        fold.feed(s)
    return (time.perf_counter() - t0) * 1e6 / len(events)


def alone() -> EventFold:
    return EventFold()


def with_page() -> EventFold:
    fold = EventFold()
    PageProjection(MemoryStatusSource(Status(robot="bench")), fold)
    return fold


def with_page_and_diagnostics() -> EventFold:
    fold = with_page()
    view = Diagnostics(COMPONENTS, fold)

    def publish(_: Stamped) -> None:  # as the ROS 2 publisher does after every change
        view.statuses()

    fold.listeners.append(publish)
    return fold


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--events", type=int, default=20000,
                        help="channel samples in the stream (default 20000)")
    parser.add_argument("--rounds", type=int, default=5, help="best of this many rounds")
    args = parser.parse_args()
    if args.events < 1 or args.rounds < 1:
        print("fold: --events and --rounds must be at least 1", file=sys.stderr)
        return 2
    events = stream(args.events)
    rows = [("the fold alone (baseline)", alone), ("the fold and the page", with_page),
            ("the fold, the page and /diagnostics", with_page_and_diagnostics)]
    best = {name: min(per_event_us(events, build) for _ in range(args.rounds))
            for name, build in rows}
    base = best[rows[0][0]]
    print(f"{len(events)} events, best of {args.rounds} rounds, load average "
          f"{os.getloadavg()[0]:.1f}\n")
    print("| per event | µs | ratio to the fold alone |\n|---|---|---|")
    for name, _ in rows:
        print(f"| {name} | {best[name]:.1f} | {best[name] / base:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
