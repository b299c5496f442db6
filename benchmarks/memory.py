"""The daemon's memory over many faults: a leak (grows with each fault) or a high-water mark?

    .venv/bin/python -m benchmarks.memory [--faults N] [--quiet-s S] [--probe] [--seed S]
        [--frames N] [--hangs-only | --trips-only]

Starts the real ``dxboard run models/tedusar --emulate`` as ``benchmarks/loop.py`` does (fast
device boots, free ports, journal in a temporary folder), waits until the robot is healthy,
then samples the daemon's resident memory (psutil) every 5 s: first over a quiet interval
(``--quiet-s``, no faults), then over ``--faults`` faults injected with ``dxboard inject``
exactly as the loop benchmark injects them (hangs in turn on hokuyo, jaguar and thermal_camera,
laser_alignment trips, a device's next fault at least ``loop.SPACING_S`` after its last,
``loop.spaced``; the next fault as soon as the robot is healthy again; ``--hangs-only``: hangs
only, each of which restarts a driver; ``--trips-only``: trips only). It prints the RSS after
each fault and the slope per fault over the first and the second half of the series: a leak
keeps its slope, a high-water mark flattens; and at the end the RSS by kind of mapping.

``--probe`` runs the daemon with ``$DXBOARD_MEMPROBE`` (``host.daemon.memprobe``): it sends
SIGUSR2 after the quiet interval, after the first fault and after the last, and prints what
grew between those snapshots — the ``tracemalloc`` top lines by growth (``--frames`` frames
each) and the live objects by type. tracemalloc itself costs memory and CPU, so RSS figures
are taken from runs without ``--probe``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import sys
import tempfile
import threading
import time
import tracemalloc
from pathlib import Path

import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout before benchmarks/

from benchmarks._rigs.robots import fast_copy, key_file
from benchmarks.loop import KINDS, TOPIC, TopicClock, ms, one_fault, schedule, spaced
from host.launch.running import RunningDaemon, healthy
from host.launch.waiting import wait_until

SAMPLE_S = 5.0


class Sampler(threading.Thread):
    """The process's RSS (MB) every SAMPLE_S seconds, with the phase it was taken in."""

    def __init__(self, proc: psutil.Process) -> None:
        super().__init__(daemon=True)
        self.proc = proc
        self.phase = "quiet"
        self.samples: list[tuple[float, str, float]] = []
        self.t0 = time.monotonic()
        self._halt = threading.Event()

    def run(self) -> None:
        while not self._halt.wait(SAMPLE_S):
            self.samples.append((time.monotonic() - self.t0, self.phase, rss_mb(self.proc)))

    def stop(self) -> None:
        self._halt.set()
        self.join()


def rss_mb(proc: psutil.Process) -> float:
    return float(proc.memory_info().rss) / 2**20


def by_mapping(pid: int) -> dict[str, float]:
    """The process's resident memory (MB) by kind of mapping: the C heap, anonymous mappings
    (Python's arenas, other threads' malloc arenas, stacks), /dev/shm, libraries, files."""
    out: dict[str, float] = {}
    kind = ""
    for line in Path(f"/proc/{pid}/smaps").read_text().splitlines():
        head = line.split()
        if re.match(r"^[0-9a-f]+-[0-9a-f]+ ", line):
            name = head[5] if len(head) > 5 else ""
            kind = ("anon" if not name else "shm" if name.startswith("/dev/shm/")
                    else "lib" if ".so" in name else name.strip("[]") if name.startswith("[")
                    else "file")
        elif head and head[0] == "Rss:":
            out[kind] = out.get(kind, 0.0) + int(head[1]) / 1024
    return {k: round(v, 1) for k, v in sorted(out.items()) if v >= 0.1}


def load_avg() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def snapshot(d: RunningDaemon, probe: Path, n: int) -> None:
    """Ask the daemon's probe for snapshot ``n`` and wait until it is written."""
    d.proc.send_signal(signal.SIGUSR2)
    wait_until(lambda: (probe / f"snap-{n}.tracemalloc").exists()
               and (probe / f"types-{n}.json").exists(), 300, f"memory snapshot {n}",
               interval=0.5)
    time.sleep(2.0)  # the dump is written in one go; let it finish before reading


def growth(probe: Path, a: int, b: int, top: int = 25) -> str:
    """What grew from snapshot ``a`` to ``b``: tracemalloc lines and object counts by type."""
    old = tracemalloc.Snapshot.load(str(probe / f"snap-{a}.tracemalloc"))
    new = tracemalloc.Snapshot.load(str(probe / f"snap-{b}.tracemalloc"))
    lines = [f"-- tracemalloc, snapshot {a} -> {b} (traced total "
             f"{sum(s.size for s in old.statistics('filename')) / 2**20:.1f} -> "
             f"{sum(s.size for s in new.statistics('filename')) / 2**20:.1f} MB)"]
    key = "traceback" if len(new.traces) and len(new.traces[0].traceback) > 1 else "lineno"
    for stat in new.compare_to(old, key)[:top]:
        lines.append(f"{stat.size_diff / 1024:+9.0f} KiB {stat.count_diff:+8d} blocks  "
                     + " <- ".join(str(f) for f in stat.traceback[:4]))
    ta = json.loads((probe / f"types-{a}.json").read_text())
    tb = json.loads((probe / f"types-{b}.json").read_text())
    diff = sorted(((tb.get(k, 0) - ta.get(k, 0), k) for k in set(ta) | set(tb)), reverse=True)
    lines.append(f"-- live objects by type, snapshot {a} -> {b}")
    lines += [f"{n:+8d} {k} ({ta.get(k, 0)} -> {tb.get(k, 0)})" for n, k in diff[:top] if n]
    return "\n".join(lines)


def slope(xs: list[float]) -> float:
    """Least-squares MB per fault over ``xs`` (RSS after each fault, in order)."""
    n = len(xs)
    if n < 2:
        return 0.0
    mx, my = (n - 1) / 2, sum(xs) / n
    return sum((i - mx) * (x - my) for i, x in enumerate(xs)) / sum((i - mx) ** 2
                                                                     for i in range(n))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--faults", type=int, default=24)
    ap.add_argument("--quiet-s", type=float, default=120.0)
    ap.add_argument("--seed", type=int, default=7)
    only = ap.add_mutually_exclusive_group()
    only.add_argument("--hangs-only", action="store_true",
                      help="only hangs, in turn on each device (each restarts a driver)")
    only.add_argument("--trips-only", action="store_true", help="only trips")
    ap.add_argument("--probe", action="store_true", help="tracemalloc snapshots in the daemon")
    ap.add_argument("--frames", type=int, default=1, help="tracemalloc frames per allocation")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        probe = tmp / "probe"
        env = {"DXBOARD_MEMPROBE": str(probe),
               "DXBOARD_MEMPROBE_FRAMES": str(args.frames)} if args.probe else {}
        d = RunningDaemon(tmp, fast_copy(tmp), extra_args=("--key-file", str(key_file(tmp))),
                          env=env)
        try:
            d.wait_for(healthy, 120, "the robot powered up and healthy")
            proc = psutil.Process(d.proc.pid)
            sampler = Sampler(proc)
            sampler.start()
            print(f"healthy: RSS {rss_mb(proc):.1f} MB, load {load_avg()}", flush=True)
            time.sleep(args.quiet_s)
            quiet = rss_mb(proc)
            print(f"after {args.quiet_s:.0f} s quiet: RSS {quiet:.1f} MB, load {load_avg()}",
                  flush=True)
            if args.probe:
                snapshot(d, probe, 1)
            sampler.phase = "faults"
            clock = TopicClock(d.zenoh, sorted(set(TOPIC.values())), d.auth)
            kind = "hang" if args.hangs_only else "trip" if args.trips_only else ""
            todo = ([(kind, KINDS[kind][i % len(KINDS[kind])]) for i in range(args.faults)]
                    if kind else schedule(args.faults, args.seed))
            after: list[float] = []
            try:
                for i, pick in enumerate(spaced(todo)):
                    s = one_fault(d, *pick, clock)
                    after.append(rss_mb(proc))
                    print(f"  {i + 1}/{args.faults} {pick[0]} {pick[1]}: healthy "
                          f"{ms(s.to_healthy)}, RSS {after[-1]:.1f} MB, load {load_avg()}",
                          flush=True)
                    if args.probe and i == 0:
                        snapshot(d, probe, 2)
            finally:
                clock.close()
            if args.probe:
                snapshot(d, probe, 3)
            sampler.stop()
            half = len(after) // 2
            print(f"resident by mapping (MB): {by_mapping(proc.pid)}")
            print(f"quiet {quiet:.1f} MB; after each fault {min(after):.1f}-{max(after):.1f} "
                  f"MB, last {after[-1]:.1f} MB; slope {slope(after[:half]):+.2f} MB/fault "
                  f"(first half), {slope(after[half:]):+.2f} MB/fault (second half)")
            print("rss samples (s, phase, MB): " + json.dumps(
                [(round(t), p, round(m, 1)) for t, p, m in sampler.samples]))
            print("rss after each fault: " + json.dumps([round(m, 1) for m in after]))
            if args.probe:
                print(growth(probe, 1, 2))
                print(growth(probe, 2, 3))
        finally:
            d.close()
    print(f"pid {os.getpid()} done, load {load_avg()}")


if __name__ == "__main__":
    main()
