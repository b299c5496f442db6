"""Ten boards into one host: the daemon's per-board pipeline, its CPU beside one board's.

    .venv/bin/python -m benchmarks.boards [--boards N] [--seconds S] [--rounds R] [--rate HZ]
        [--hold-ms MS] [--per-frame K,...] [--label TEXT] [--write]

The daemon handles one board; this measures what one board costs it, ten times over in one
process, as the daemon wires it (``host.daemon.core``): per board a ``BoardClient`` subscribed
at ``--rate`` (default 100 Hz) whose every item goes to an ``ObserverHub`` holding the
hardware observer of ``models/tedusar/system.yaml``; the hub's updates are folded into an
``ObservationSet`` (``fold_updates``) and a ``DiagnosisRunner`` diagnoses it on every change
and on its 2 s safety tick, off the loop. The boards are ``dxboard emulate models/tedusar``
subprocesses (10 channels each; not counted: a real board is not the host's CPU).

All ``--boards`` emulators are started first, so the machine carries the same load in both
phases of one run:

1. baseline: the pipeline of one board, for ``--seconds`` (default 20);
2. the pipelines of every board, for as long.

Both phases ``--rounds`` times, interleaved (the load of a shared machine drifts; medians),
and both once for every ``--per-frame`` (default ``default``: the board client's own choice,
``default_per_frame``; a number K opens the boards as ``...?per_frame=K``, 1 being one reading
a frame as before batching), so the choices are compared in the same run.
For each phase: this process's CPU (user + system, psutil, every thread: the diagnosis worker
too) as a share of one core, readings received a second, readings missed (the gaps in the
boards' numbering plus those the host dropped, ``Reading.missed``); at the end of the last
phase one injected overcurrent of laser_alignment per board: fault → the first diagnosis
naming it. ``--hold-ms`` opens the boards as ``tcp://...?hold_ms=MS`` (reading held that long
after each arrival: fewer wake-ups, that much more latency). Target
(issue 18, item 2): ten boards x 10 channels x 100 Hz at <= 5 % of one core, 0 missed.
``--write`` replaces the '### Ten boards: the latest run' part of the '## Daemon loop' section
of benchmarks/RESULTS.md (or appends it there; the earlier tables stay).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout before benchmarks/

from benchmarks._rigs.robots import KEY
from benchmarks.loop import start_board, stop_boards
from host.board import BoardClient
from host.board.types import Reading
from host.diagnosis import Diagnoser, generate, load_system
from host.diagnosis.observations import ObservationSet
from host.diagnosis.runner import DiagnosisRunner, fold_updates
from host.events import DiagnosisRecord, Event
from host.launch.running import TEDUSAR
from host.observers import ObserverHub, load_observers
from host.observers.base import Update
from host.observers.hardware import HardwareObserver
from host.transports.errors import BoardRefused

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "RESULTS.md"
HEADING = "### Ten boards: the latest run"  # --write replaces only this section
SETTLE_S = 4.0  # after subscribing: connected, devices switched on, literals settled
DEVICES_ON = ("laser_alignment", "hokuyo", "jaguar")  # switched on first (off by default)
FAULT = ("laser_alignment", "overcurrent", "amps=5")


class Pipeline:
    """One board's share of the daemon: client → hub (hardware observer) → set → diagnosis."""

    def __init__(self, url: str, rate_hz: int) -> None:
        self.url = url
        self.per_frame = 0  # what the client asked the board for
        self.rate_hz = rate_hz
        model = load_system(TEDUSAR)
        theory = generate(model)
        cfg = load_observers(TEDUSAR, model)
        hardware = [o for o in cfg.observers if isinstance(o, HardwareObserver)]
        self.known = theory.observable_atoms()
        self.observations = ObservationSet()
        self.hub = ObserverHub(hardware, self._updates)
        self.runner = DiagnosisRunner(Diagnoser(theory), self.observations, self._emit)
        self.readings = 0
        self.missed = 0
        self.named: dict[str, float] = {}  # component -> monotonic time first named

    def _updates(self, updates: list[Update]) -> None:
        if fold_updates(updates, self.observations, self.known, self._emit):
            self.runner.poke()

    def _emit(self, event: Event) -> None:
        if isinstance(event, DiagnosisRecord):
            now = time.monotonic()
            for bad in event.diagnoses:
                for c in bad:
                    self.named.setdefault(c, now)

    async def run(self) -> None:
        """Connect, switch the devices on, then feed the hub as the daemon's board task does."""
        diagnosis = asyncio.ensure_future(self.runner.task())
        try:
            async with BoardClient(self.url, KEY) as client:
                for name in DEVICES_ON:
                    # tripped, or latched, by an earlier phase's fault: clear, off, on
                    with contextlib.suppress(BoardRefused):
                        await client.clear(name)
                    await client.switch(name, False)
                    await client.switch(name, True)
                self.hub.feed_board(await client.state())
                async for item in client.subscribe(self.rate_hz):
                    self.per_frame = client.per_frame
                    if isinstance(item, Reading):
                        self.readings += 1
                        self.missed += item.missed
                    self.hub.feed_board(item)
        finally:
            diagnosis.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await diagnosis
            await self.hub.close()
            self.runner.close()



@dataclass
class PhaseResult:
    boards: int
    per_frame: str = ""
    seconds: float = 0.0
    cpu: float = 0.0  # share of one core
    readings_per_s: float = 0.0
    missed: int = 0
    to_diagnosis: list[float] = field(default_factory=list)
    undiagnosed: int = 0


def cpu_seconds(me: psutil.Process) -> float:
    t = me.cpu_times()
    return float(t.user + t.system)


async def inject(control: str) -> None:
    await asyncio.to_thread(subprocess.run, [
        sys.executable, "-m", "host.cli", "inject", control, *FAULT], check=True, cwd=ROOT,
        capture_output=True, timeout=60)


async def clear(control: str) -> None:
    await asyncio.to_thread(subprocess.run, [
        sys.executable, "-m", "host.cli", "inject", control, "clear"], check=True, cwd=ROOT,
        capture_output=True, timeout=60)


def query(hold_ms: int, per_frame: str) -> str:
    """The board URL's query for a phase: ``hold_ms`` if any, ``per_frame`` unless default."""
    params = [f"hold_ms={hold_ms}"] if hold_ms else []
    if per_frame != "default":
        params.append(f"per_frame={int(per_frame)}")
    return "?" + "&".join(params) if params else ""


async def phase(boards: list[tuple[subprocess.Popen[str], dict[str, str]]],
                seconds: float, rate_hz: int, faults: bool, hold_ms: int = 0,
                per_frame: str = "default") -> PhaseResult:
    """The pipelines of ``boards`` for ``seconds``, then (``faults``) one fault per board."""
    res = PhaseResult(len(boards))
    pipes = [Pipeline(urls["board"] + query(hold_ms, per_frame), rate_hz)
             for _, urls in boards]
    tasks = [asyncio.ensure_future(p.run()) for p in pipes]
    try:
        await asyncio.sleep(SETTLE_S)
        me = psutil.Process()
        r0, m0 = sum(p.readings for p in pipes), sum(p.missed for p in pipes)
        c0, t0 = cpu_seconds(me), time.monotonic()
        await asyncio.sleep(seconds)
        c1, t1 = cpu_seconds(me), time.monotonic()
        r1, m1 = sum(p.readings for p in pipes), sum(p.missed for p in pipes)
        res.seconds = t1 - t0
        res.cpu = (c1 - c0) / res.seconds
        res.readings_per_s = (r1 - r0) / res.seconds
        res.missed = m1 - m0
        asked = sorted({p.per_frame for p in pipes})
        res.per_frame = per_frame if per_frame != "default" else \
            "default (" + ",".join(map(str, asked)) + ")"
        for p, (_, urls) in zip(pipes, boards if faults else [], strict=False):
            p.named.pop(FAULT[0], None)
            await inject(urls["control"])
            t_inj = time.monotonic()
            deadline = t_inj + 10.0
            while FAULT[0] not in p.named and time.monotonic() < deadline:
                await asyncio.sleep(0.01)
            if FAULT[0] in p.named:
                res.to_diagnosis.append(p.named[FAULT[0]] - t_inj)
            else:
                res.undiagnosed += 1
            await clear(urls["control"])
    finally:
        for t in tasks:
            t.cancel()
        for t in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await t  # a pipeline that failed raises here: no figure from a broken run
    return res


async def run(n: int, seconds: float, rate_hz: int, rounds: int, hold_ms: int = 0,
              per_frames: tuple[str, ...] = ("default",)
              ) -> list[tuple[list[PhaseResult], list[PhaseResult]]]:
    """``rounds`` times, for each of ``per_frames``, one board then every board, interleaved
    (the machine's load drifts: each kind sees the same drift); the faults in the last round
    (each cleared after it is diagnosed). One (ones, alls) pair per ``per_frames`` entry."""
    boards = [start_board(TEDUSAR) for _ in range(n)]
    out: list[tuple[list[PhaseResult], list[PhaseResult]]] = [([], []) for _ in per_frames]
    try:
        for r in range(rounds):
            last = r == rounds - 1
            for (ones, alls), k in zip(out, per_frames, strict=True):
                ones.append(await phase(boards[:1], seconds, rate_hz, False, hold_ms, k))
                print(f"  round {r + 1}, 1 board, per_frame {ones[-1].per_frame}: "
                      f"{fmt(ones[-1])}", flush=True)
                alls.append(await phase(boards, seconds, rate_hz, last, hold_ms, k))
                print(f"  round {r + 1}, {n} boards, per_frame {alls[-1].per_frame}: "
                      f"{fmt(alls[-1])}", flush=True)
        return out
    finally:
        stop_boards(boards)


def ms(xs: list[float], q: float) -> str:
    if not xs:
        return "-"
    s = sorted(xs)
    return f"{s[min(len(s) - 1, int(q / 100 * len(s)))] * 1000:.0f} ms"


def fmt(r: PhaseResult) -> str:
    return (f"CPU {r.cpu * 100:.1f} % of one core, {r.readings_per_s:.0f} readings/s, "
            f"missed {r.missed}, fault → diagnosis p50 {ms(r.to_diagnosis, 50)} max "
            f"{ms(r.to_diagnosis, 100)} ({r.undiagnosed} not diagnosed)")


def row(label: str, rs: list[PhaseResult]) -> str:
    """One kind of phase over the rounds: CPU median (min-max), readings, missed, faults."""
    cpus = sorted(r.cpu * 100 for r in rs)
    mid = statistics.median(cpus)
    n = rs[0].boards
    diag = [d for r in rs for d in r.to_diagnosis]
    per_s = statistics.median(r.readings_per_s for r in rs)
    us = mid / 100 / per_s * 1e6 if per_s else float("nan")
    return (f"| {label} | {rs[0].per_frame} | {n} | {len(rs)} x {rs[0].seconds:.0f} | "
            f"{mid:.1f} ({cpus[0]:.1f}-{cpus[-1]:.1f}) | {mid / n:.2f} | {us:.0f} | "
            f"{per_s:.0f} | {sum(r.missed for r in rs)} | {ms(diag, 50)} / {ms(diag, 100)} |")


def report(results: list[tuple[list[PhaseResult], list[PhaseResult]]],
           args: argparse.Namespace, load: str, label: str) -> str:
    """The table (one board and every board, per ``--per-frame``); the target is judged on
    the first ``--per-frame`` (the default)."""
    rows = ["| run | per_frame | boards | rounds x s | CPU, % of one core: median (min-max) | "
            "per board | µs a reading | readings/s | missed | fault → diagnosis p50 / max |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for ones, alls in results:
        rows += [row(label, ones), row(label, alls)]
    ones, alls = results[0]
    base = statistics.median(r.cpu for r in ones)
    cpu = statistics.median(r.cpu for r in alls)
    met = cpu <= 0.05 and sum(r.missed for r in alls) == 0 and \
        sum(r.undiagnosed for r in alls) == 0 and \
        min(r.readings_per_s for r in alls) >= 0.95 * args.boards * args.rate
    return f"""{HEADING}

`.venv/bin/python -m benchmarks.boards --boards {args.boards} --seconds {args.seconds:g} \
--rounds {args.rounds}{f" --hold-ms {args.hold_ms}" if args.hold_ms else ""} \
--per-frame {",".join(args.per_frame)}` \
({platform.python_implementation()} {platform.python_version()}, {os.cpu_count()} cores \
shared with other engineers' work; load average {load}).

{chr(10).join(rows)}

{args.boards} boards cost {cpu / base if base else float('nan'):.1f}x one board \
(medians, measured in the same run). Target: {args.boards} boards at <= 5 % of one core, \
0 readings missed — {'**met**' if met else '**not met**'}.
"""


def write(text: str) -> None:
    """Replace HEADING's part of RESULTS.md (or append it to '## Daemon loop')."""
    old = RESULTS.read_text()
    pat = re.compile(rf"^{re.escape(HEADING)}\n.*?(?=^## |^### |\Z)", re.S | re.M)
    if pat.search(old):
        new = pat.sub(lambda _: text + "\n", old, count=1)
    else:
        at = re.search(r"^## (?!Daemon loop)", old[old.index("## Daemon loop"):], re.M)
        cut = old.index("## Daemon loop") + (at.start() if at else len(old))
        new = old[:cut].rstrip("\n") + "\n\n" + text + "\n" + old[cut:]
    RESULTS.write_text(new)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--boards", type=int, default=10)
    ap.add_argument("--seconds", type=float, default=20.0, help="each phase (default 20)")
    ap.add_argument("--rate", type=int, default=100, help="subscription, Hz (default 100)")
    ap.add_argument("--rounds", type=int, default=3, help="of both phases (default 3)")
    ap.add_argument("--hold-ms", type=int, default=0,
                    help="tcp:// reading held this long after each arrival (default 0: off)")
    ap.add_argument("--per-frame", type=lambda t: tuple(t.split(",")), default=("default",),
                    help="readings a frame to compare, e.g. default,1 (default: default)")
    ap.add_argument("--label", default="this branch", help="the run's name in the table")
    ap.add_argument("--write", action="store_true", help="write benchmarks/RESULTS.md")
    args = ap.parse_args()
    load = " ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"{args.boards} boards, {args.seconds:g} s a phase, load average {load}", flush=True)
    for k in args.per_frame:
        if k != "default" and not (k.isdigit() and 1 <= int(k) <= 10):
            ap.error(f"--per-frame {k}: each must be 'default' or a number 1..10")
    results = asyncio.run(run(args.boards, args.seconds, args.rate, args.rounds,
                              args.hold_ms, args.per_frame))
    load = load + " → " + " ".join(Path("/proc/loadavg").read_text().split()[:3])
    text = report(results, args, load, args.label)
    print(text)
    if args.write:
        write(text)
    print(json.dumps({f"{rs[0].boards} boards, per_frame {rs[0].per_frame}": [r.cpu for r in rs]
                      for pair in results for rs in pair}))


if __name__ == "__main__":
    main()
