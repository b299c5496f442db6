"""No flapping under load: false diagnoses and repairs of a healthy robot on a busy machine.

    .venv/bin/python -m benchmarks.flap [--quick] [--middleware zenoh|ros2] [--minutes M]
        [--idle-minutes M] [--faults N] [--idle-faults N] [--own-time on|off] [--keep DIR]
        [--write]

The real daemon, ``dxboard run models/tedusar --emulate`` (a subprocess, as ``tests/daemon``:
free ports, short device boot times, journal in a temporary folder; the board streams 10
channels at 100 Hz, the nodes run as real processes), is left alone with a healthy robot.
``--middleware ros2`` runs the ROS 2 robot as ``make run`` starts it (``dxboard run
--middleware ros2``: the nodes real ROS 2 nodes, the lidar's driver a managed one), on a DDS
domain of the benchmark's own (``host.launch.domains``), watched by an independent rclpy peer
(``benchmarks.ros_arrivals``) instead of a Zenoh one; default: the Zenoh robot.

1. baseline, the idle machine (``--idle-minutes``, default 3; quick 0.5);
2. the same with a CPU hog on every core beside it (``--minutes``, default 10; quick 1): one
   busy-looping process per core (``os.cpu_count()``), each ending by itself after the phase
   and killed by the benchmark at its end in any case (``--minutes 0``: no hog at all, for
   hang figures on the idle machine alone);
3. still under the hog, ``--faults`` hokuyo hangs (default 3; quick 1; with ``--minutes 0``
   none unless asked, which starts the hog for them), each found through
   /scan falling silent and repaired: fault → diagnosis and fault → verified healthy.

For phases 1 and 2, from the journal: every topic observation that went false (``~ok(/t)``:
a frequency observer's verdict), every other abnormal literal (``~link(board)``...), every link
drop of the board client itself (``LinkChange``: a reconnect), every diagnosis naming any
component (a healthy robot has none: each is false) and every repair action started (each is
a false repair). Target: 0 false
diagnoses and 0 repairs under the hog. ``--write`` replaces the '## No flapping under load'
section of benchmarks/RESULTS.md. ``--idle-faults N`` adds N hangs on the idle machine (between
phases 1 and 2): hang detection on the machine as quiet as it is. ``--own-time off`` judges
every topic's silence as before this rule (``own_time: false`` in the robot copy's
``system.yaml``): the baseline of the same session. ``--keep DIR`` runs in DIR (created) and
leaves the daemon's journal (``journal.sqlite``) and its log (``daemon.err``: each silence
with the publisher's own time and run-queue wait; each rate verdict withheld because the
publisher was held on the run queue) there, to trace every false verdict; the log's silence
and withheld-rate lines are printed at the end.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, cast

import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout before benchmarks/

from benchmarks._rigs.robots import fast_copy, key_file
from benchmarks.loop import (
    Sample,
    TopicClock,
    arrival_stamper,
    cpu_of,
    gap_around,
    ms,
    one_fault,
    pct,
    write_section,
)
from host.journal import ActionRecord, DiagnosisRecord, LinkChange, Observation
from host.launch.domains import claim_domain, domain_env
from host.launch.running import RunningDaemon, healthy

TOPICS = ["/scan", "/imu_data", "/odom", "/cmd_vel", "/map", "/thermal/image"]

HOG = "import time\nend = time.monotonic() + {s}\nwhile time.monotonic() < end:\n    pass\n"


@dataclass
class Phase:
    name: str
    seconds: float = 0.0
    flips: dict[str, int] = field(default_factory=dict)  # topic literal -> times it went false
    others: dict[str, int] = field(default_factory=dict)  # any other literal -> times false
    diagnoses: int = 0  # diagnoses naming a component (a healthy robot: each one is false)
    repairs: int = 0  # repair actions started
    link_drops: dict[str, int] = field(default_factory=dict)  # the client's, by reason
    named: set[str] = field(default_factory=set)
    loads: list[float] = field(default_factory=list)  # the 1-minute load average, every 10 s
    daemon_cpu: float = 0.0  # the daemon process's CPU over the phase, percent of one core
    abnormal: list[tuple[float, float, str]] = field(default_factory=list)  # wall, mono, ±lit

    def load(self) -> str:
        v = sorted(self.loads)
        return f"{v[0]:.1f} / {v[len(v) // 2]:.1f} / {v[-1]:.1f}" if v else "-"


def loadavg() -> float:
    """The machine's 1-minute load average (never quiet: said beside every figure)."""
    try:
        return float(Path("/proc/loadavg").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return float("nan")


@contextlib.contextmanager
def hogs(seconds: float) -> Iterator[list[subprocess.Popen[bytes]]]:
    """One busy loop per core, each bounded to ``seconds`` (+ a margin), killed on exit."""
    procs = [subprocess.Popen([sys.executable, "-c", HOG.format(s=seconds + 60)])
             for _ in range(os.cpu_count() or 1)]
    try:
        yield procs
    finally:
        for p in procs:
            p.kill()
        for p in procs:
            p.wait()


class Arrivals(TopicClock):
    """An independent Zenoh peer that keeps every arrival time (CLOCK_MONOTONIC, as the
    journal's ``mono``) of the observed topics: was a gap the daemon called silent seen by
    another subscriber too?"""

    def __init__(self, endpoint: str, topics: list[str], auth: Path | None = None) -> None:
        self.times: dict[str, list[float]] = {t: [] for t in topics}
        super().__init__(endpoint, topics, auth)

    def _stamper(self, topic: str) -> Callable[[object], None]:
        return arrival_stamper(self.last, self.times[topic], topic)

    def gap(self, topic: str, mono: float) -> tuple[float, float] | None:
        """The gap around ``mono`` as this peer saw it: (last arrival before, next after)."""
        return gap_around(self.times.get(topic, []), mono)


class Peer(Protocol):
    """An independent subscriber of the robot's topics (Zenoh or ROS 2)."""

    last: dict[str, float]

    def gap(self, topic: str, mono: float) -> tuple[float, float] | None: ...

    def close(self) -> None: ...


def trace(ph: Phase, peer: Peer | None, log: Path | None) -> list[str]:
    """One line per abnormal literal of a phase: what the independent peer saw of the topic
    then, and the daemon's own log line about it."""
    lines = log.read_text(errors="replace").splitlines() if log and log.exists() else []
    out = []
    for wall, mono, lit in ph.abnormal:
        topic = lit[4:-1] if lit.startswith("~ok(/") else None
        seen = peer.gap(topic, mono) if peer is not None and topic else None
        stamp = time.strftime("%H:%M:%S", time.gmtime(wall))
        said = [ln for ln in lines if topic and f"frequency:{topic}:" in ln
                and stamp in ln[:30]]
        out.append(f"{lit} at {stamp}: " + (
            f"the peer saw no {topic} for {1000 * (seen[1] - seen[0]):.0f} ms "
            f"({1000 * (mono - seen[0]):.0f} ms before the verdict to "
            f"{1000 * (seen[1] - mono):.0f} ms after)" if seen else "no peer gap")
            + (f"; daemon: {said[-1].split(': ', 2)[-1]}" if said else ""))
    return out


def watch(d: RunningDaemon, name: str, seconds: float) -> Phase:
    """Leave the healthy robot alone for ``seconds``; what the journal says happened."""
    d.caught_up()
    mark = max((e.id for e in d.journal()), default=0)
    t0 = time.monotonic()
    end = t0 + seconds
    loads = [loadavg()]
    proc = psutil.Process(d.proc.pid)
    c0 = cpu_of([proc])
    while (left := end - time.monotonic()) > 0:
        time.sleep(min(left, 10.0))
        loads.append(loadavg())
    d.caught_up()
    ph = Phase(name, time.monotonic() - t0, loads=loads)
    ph.daemon_cpu = 100 * (cpu_of([proc]) - c0) / ph.seconds
    started: set[str] = set()
    for e in d.journal():
        if e.id <= mark:
            continue
        p = e.payload
        if isinstance(p, Observation) and p.literal.startswith("ok(/") and p.value is False:
            ph.flips[p.literal] = ph.flips.get(p.literal, 0) + 1
            ph.abnormal.append((e.wall, e.mono, "~" + p.literal))
        elif isinstance(p, Observation) and p.value is not None and \
                p.value == p.literal.startswith("tripped("):  # an abnormal reading
            ph.others[p.literal] = ph.others.get(p.literal, 0) + 1
            ph.abnormal.append((e.wall, e.mono, ("" if p.value else "~") + p.literal))
        elif isinstance(p, DiagnosisRecord) and any(p.diagnoses):
            ph.diagnoses += 1
            ph.named.update(c for bad in p.diagnoses for c in bad)
        elif isinstance(p, ActionRecord):
            started.add(p.action_id)
        elif isinstance(p, LinkChange) and not p.up:  # the client dropped the link itself
            why = p.reason.split(":")[-1].strip()[:60]
            ph.link_drops[why] = ph.link_drops.get(why, 0) + 1
    ph.repairs = len(started)
    print(f"  {name}: {ph.seconds:.0f} s, topic verdicts ~ok {sum(ph.flips.values())} "
          f"{ph.flips or ''}, other abnormal literals {ph.others or 0}, false diagnoses "
          f"{ph.diagnoses} naming {sorted(ph.named)}, repairs {ph.repairs}, the client's link "
          f"drops {ph.link_drops or 0}, load average (1 min) min/median/max {ph.load()}, "
          f"the daemon's CPU {ph.daemon_cpu:.1f} % of one core",
          flush=True)
    return ph


@contextlib.contextmanager
def workdir(keep: Path | None) -> Iterator[Path]:
    """``keep`` (created, left behind) or a temporary folder."""
    if keep is not None:
        keep.mkdir(parents=True, exist_ok=True)
        yield keep
        return
    with tempfile.TemporaryDirectory() as tmpdir:
        yield Path(tmpdir)


def without_own_time(system_dir: Path) -> None:
    """Every topic of ``system_dir``'s observers judged as before (``own_time: false``)."""
    f = system_dir / "system.yaml"
    f.write_text(re.sub(r"(?m)^(    /[^:]+: \{[^}]*)\}", r"\1, own_time: false}",
                        f.read_text()))


@contextlib.contextmanager
def robot(tmp: Path, own_time: bool, middleware: str = "zenoh"
          ) -> Iterator[tuple[RunningDaemon, Peer]]:
    """The fast virtual TEDUSAR robot (``benchmarks._rigs.robots.healthy_robot``) on
    ``middleware`` (on ROS 2 in a DDS domain of its own), its topics' silences judged in the
    publishers' own time or not; and an independent peer watching its topics."""
    system = fast_copy(tmp)
    if not own_time:
        without_own_time(system)
    with contextlib.ExitStack() as stack:
        domain = stack.enter_context(claim_domain()) if middleware == "ros2" else None
        env = domain_env(domain) if domain is not None else {}
        d = RunningDaemon(tmp, system, env=env, extra_args=(
            "--key-file", str(key_file(tmp)), "--middleware", middleware))
        stack.callback(d.close)
        d.wait_for(healthy, 120, "the robot powered up and healthy")
        peer: Peer
        if domain is not None:
            from benchmarks.ros_arrivals import RosArrivals
            peer = RosArrivals(domain, TOPICS)
        else:
            peer = Arrivals(d.zenoh, TOPICS, d.auth)
        stack.callback(peer.close)
        yield d, peer


SPACING_S = 65.0  # between two hangs of the lidar: the repair limiter's 60 s, and a margin


def hangs(d: RunningDaemon, clock: Peer, n: int, where: str) -> list[Sample]:
    """``n`` hokuyo hangs, each ``SPACING_S`` after the last (a repair of the same device
    again within the limiter's minute counts as one that did not hold)."""
    out: list[Sample] = []
    last = time.monotonic() - SPACING_S
    for i in range(n):
        time.sleep(max(0.0, last + SPACING_S - time.monotonic()))
        last = time.monotonic()
        load = loadavg()
        s = one_fault(d, "hang", "hokuyo", cast(TopicClock, clock))
        out.append(s)
        print(f"  fault {i + 1}/{n} ({where}, load {load:.1f}): last /scan seen → ~ok "
              f"{ms(s.silence)}, fault → ~ok {ms(s.detect)}, fault → diagnosis "
              f"{ms(s.to_diagnosis)}, healthy {ms(s.to_healthy)}", flush=True)
    return out


def run(idle_s: float, hog_s: float, n_faults: int, keep: Path | None = None,
        idle_faults: int = 0, own_time: bool = True, middleware: str = "zenoh"
        ) -> tuple[list[Phase], list[Sample], list[Sample]]:
    phases: list[Phase] = []
    hog: list[Sample] = []
    with workdir(keep) as tmp, robot(tmp, own_time, middleware) as (d, clock):
        phases.append(watch(d, "idle machine", idle_s))
        idle = hangs(d, clock, idle_faults, "idle machine")
        if hog_s > 0 or n_faults > 0:
            with hogs(hog_s + n_faults * SPACING_S):
                phases.append(watch(d, f"CPU hog on {os.cpu_count()} cores", hog_s))
                hog = hangs(d, clock, n_faults, "under the hog")
        for ph in phases:
            for line in trace(ph, clock, tmp / "daemon.err"):
                print(f"  trace ({ph.name}): {line}", flush=True)
    return phases, idle, hog


def hang_line(samples: list[Sample], where: str) -> str:
    diag = [s.to_diagnosis for s in samples if s.to_diagnosis is not None]
    heal = [s.to_healthy for s in samples if s.to_healthy is not None]
    sil = [s.silence for s in samples if s.silence is not None]
    det = [s.detect for s in samples if s.detect is not None]
    return (f"- Injected faults {where}: {len(samples)} hokuyo hang(s), {len(diag)} diagnosed "
            f"(last /scan seen → ~ok p50 {ms(pct(sil, 50))}, max {ms(max(sil) if sil else None)};"
            f" fault → ~ok p50 {ms(pct(det, 50))}, max {ms(max(det) if det else None)};"
            f" fault → diagnosis p50 {ms(pct(diag, 50))}, max "
            f"{ms(max(diag) if diag else None)}), {len(heal)} verified healthy again (p50 "
            f"{ms(pct(heal, 50))}, max {ms(max(heal) if heal else None)}).")


def report(phases: list[Phase], idle: list[Sample], samples: list[Sample],
           args: argparse.Namespace) -> str:
    rows = ["| phase | minutes | topic verdicts ~ok (by topic) | other abnormal literals | "
            "the client's link drops | false diagnoses (naming) | repairs | load (1 min) "
            "min / median / max |",
            "|---|---|---|---|---|---|---|---|"]
    for ph in phases:
        by = ", ".join(f"{k} {v}" for k, v in sorted(ph.flips.items())) or "none"
        other = ", ".join(f"`{k}` {v}" for k, v in sorted(ph.others.items())) or "none"
        drops = sum(ph.link_drops.values())
        rows.append(f"| {ph.name} | {ph.seconds / 60:.1f} | {sum(ph.flips.values())} ({by}) | "
                    f"{other} | {drops} | {ph.diagnoses} "
                    f"({', '.join(sorted(ph.named)) or '-'}) | {ph.repairs} | {ph.load()} |")
    hog = phases[-1]
    met = hog.diagnoses == 0 and hog.repairs == 0
    cmd = (" --quick" if args.quick else "") + ("" if args.own_time == "on" else
                                                  " --own-time off")
    cmd += f" --middleware {args.middleware}" if args.middleware != "zenoh" else ""
    return f"""## No flapping under load

`.venv/bin/python -m benchmarks.flap{cmd} --minutes {args.minutes:g} --idle-minutes \
{args.idle_minutes:g} --write` ({platform.python_implementation()} \
{platform.python_version()}, {os.cpu_count()} cores shared with other engineers' work). The \
real `dxboard run models/tedusar --emulate --middleware {args.middleware}` with a healthy \
robot (board at 10 channels x 100 Hz, 9 node processes publishing /imu_data at 100 Hz, \
/scan 40, /odom 20, /cmd_vel 10, /map 0.5), left alone on the idle machine (the baseline), \
then beside one busy-looping process per core. Counted from the journal: frequency verdicts \
`~ok(/t)`, other abnormal literals (`~link(board)` among them), the board client's own \
link drops (a reconnect), diagnoses naming any component (each false: nothing is broken) \
and repair actions started.

{chr(10).join(rows)}

- Target under the hog: 0 false diagnoses and 0 repairs — {'**met**' if met else '**NOT met**'}.
{hang_line(idle, "on the idle machine") if idle else ""}
{hang_line(samples, "under the hog") if samples else ""}
- Before (issue 18): a headless browser starting beside the daemon flipped `ok(/imu_data)` \
and `ok(/scan)` about 20 times in a second; only the repair debounce kept them from a repair. \
The frequency observer now judges the rate on the publishers' stamps and a silence in the \
publishers' own time, their run-queue wait left out (`host/observers/topics.py`, \
`host/observers/starvation.py`); the simulated-clock proofs are \
`tests/observers/test_jitter.py` and `tests/observers/test_starved.py`. The board's link \
rule learns the gaps between readings (`host/observers/hardware.py`, \
`tests/observers/test_link_jitter.py`).
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="a fast check: 1 min, 1 fault")
    ap.add_argument("--minutes", type=float, default=None, help="under the hog (default 10)")
    ap.add_argument("--idle-minutes", type=float, default=None, help="baseline (default 3)")
    ap.add_argument("--faults", type=int, default=None,
                    help="hangs under the hog (default 3; 0 with --minutes 0)")
    ap.add_argument("--keep", type=Path, default=None, metavar="DIR",
                    help="run in DIR and keep the journal and the daemon's log there")
    ap.add_argument("--idle-faults", type=int, default=0,
                    help="hangs on the idle machine, before the hog (default 0)")
    ap.add_argument("--own-time", choices=("on", "off"), default="on",
                    help="off: every topic's silence judged as before (own_time: false)")
    ap.add_argument("--middleware", choices=("zenoh", "ros2"), default="zenoh",
                    help="the robot's middleware (ros2: as `make run` starts it)")
    ap.add_argument("--write", action="store_true", help="write benchmarks/RESULTS.md")
    args = ap.parse_args()
    if args.minutes is None:
        args.minutes = 1.0 if args.quick else 10.0
    if args.idle_minutes is None:
        args.idle_minutes = 0.5 if args.quick else 3.0
    n = args.faults if args.faults is not None else (
        0 if args.minutes == 0 else 1 if args.quick else 3)  # --minutes 0: no hog at all
    print(f"idle {args.idle_minutes:g} min, hog {args.minutes:g} min, {n} faults", flush=True)
    phases, idle, samples = run(args.idle_minutes * 60, args.minutes * 60, n, args.keep,
                                args.idle_faults, args.own_time == "on", args.middleware)
    text = report(phases, idle, samples, args)
    print(text)
    if args.keep is not None:
        log = args.keep / "daemon.err"
        lines = log.read_text(errors="replace").splitlines() if log.exists() else []
        print(f"silences in {log}:", *[ln for ln in lines if ": silent" in ln], sep="\n  ")
        print(f"rate verdicts withheld (publisher held up) in {log}:",
              *[ln for ln in lines if "no rate verdict" in ln], sep="\n  ")
    if args.write:
        write_section(text, "## No flapping under load")
    print(json.dumps({p.name: {"flips": sum(p.flips.values()), "diagnoses": p.diagnoses,
                               "repairs": p.repairs} for p in phases}))


if __name__ == "__main__":
    main()
