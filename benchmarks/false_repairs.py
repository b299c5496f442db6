"""False repairs under the faults of issue 25, item 7: how many in N runs of each.

Each case runs the fast virtual TEDUSAR robot under a real ``dxboard run`` (the same runner the
tests use, ``host.launch.running``) and counts, per run, the *false repairs*: actions that
switch a healthy device's power (``power_cycle``, ``power_up``, ``shutdown``), quarantines, and
for the freeze a note that the board refused the daemon's key.

- **brown-out**: ``inject board brownout volts=20 seconds=3``; the board sheds its channels and
  restores them itself. Restarting the drivers that lost their devices is the repair; switching a
  restored device again is false.
- **freeze**: ``inject board link_freeze seconds=5``; nothing is wrong with any device or the
  key.
- **kill -9 + restart**: a board that runs on its own (``dxboard emulate --robot``); a daemon
  brings the robot up, is killed with SIGKILL, and the next daemon starts. It must start the
  nodes and nothing else: a power action or a ``stop_node`` of a node it started is false.
- **sensor noise**: ``inject hokuyo sensor_noise amps=A`` for ``--noise-s`` seconds; the lidar is
  fine, only its current reading is noisy.

One daemon serves the brown-out, freeze and noise runs (healthy again between runs); the
restart case uses a daemon per run. Goal: 0 false repairs in 10 runs of each. A run after which
the robot is not healthy again within ``HEAL_S`` (a heavily loaded machine) is counted apart,
with what it did until then still counted.

    .venv/bin/python -m benchmarks.false_repairs [--runs N] [--cases a,b] [--noise-amps A]
    .venv/bin/python benchmarks/false_repairs.py ... [--write]

``--write`` appends the table, with the date and the load average, to benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks._rigs.robots import fast_copy, healthy_robot, key_file  # noqa: E402
from host.events import LinkChange  # noqa: E402
from host.journal import QuarantineChange  # noqa: E402
from host.launch.boards import RunningBoard, daemon_on  # noqa: E402
from host.launch.running import (  # noqa: E402
    RunningDaemon,
    actions_started,
    healthy,
    last_id,
    node_processes,
)
from host.launch.waiting import wait_until  # noqa: E402

POWER = ("power_cycle", "power_up", "shutdown")
HEAL_S = 120.0
UNHEALED = "not healthy again within the wait"  # counted apart: not a false repair
CASES = ("brownout", "freeze", "restart", "noise")


def false_since(d: RunningDaemon, mark: int, extra: tuple[str, ...] = ()) -> list[str]:
    """The false repairs journalled after ``mark``: power actions (and ``extra`` actions),
    quarantines, key-refusal notes."""
    d.caught_up()
    out = [a for a in actions_started(d, mark) if a.split("(")[0] in POWER + extra]
    for e in d.journal(("quarantine", "link")):
        p = e.payload
        if e.id <= mark:
            continue
        if isinstance(p, QuarantineChange) and p.quarantined:
            out.append(f"quarantine({p.component})")
        elif isinstance(p, LinkChange) and p.up and p.key.startswith("refused"):
            out.append("key refused")  # said on the terminal, the page and the journal
    return out


def brownout(d: RunningDaemon) -> None:
    d.inject("board", "brownout", "volts=20", "seconds=3")
    d.settled(6.0)
    d.wait_for(healthy, HEAL_S, "healthy after the brown-out")
    d.settled(2.0)


def freeze(d: RunningDaemon) -> None:
    d.inject("board", "link_freeze", "seconds=5")
    d.wait_for(lambda s: not s["board_link_up"], 30.0, "the link judged lost")
    d.wait_for(lambda s: s["board_link_up"] and healthy(s), HEAL_S, "healthy after the freeze")
    d.settled(2.0)


def noise(d: RunningDaemon, amps: float, seconds: float) -> None:
    d.inject("hokuyo", "sensor_noise", f"amps={amps:g}")
    try:
        d.settled(seconds, runs=4)
    finally:
        d.inject("clear")
    for name in d.status()["quarantined"]:  # the next run starts from a healthy robot
        d.operator("quarantine", "clear", name)
    d.wait_for(healthy, HEAL_S, "healthy after the noise")


def one_run(d: RunningDaemon, case: str, amps: float, noise_s: float) -> list[str]:
    """One run of ``case`` on the shared daemon: its false repairs (and ``UNHEALED``)."""
    unhealed = []
    try:
        d.wait_for(healthy, HEAL_S, "healthy before the run")
        d.inject("clear")  # an injected fault stays set: the same one again would be no change
        mark = last_id(d)
        try:
            (noise(d, amps, noise_s) if case == "noise" else
             brownout(d) if case == "brownout" else freeze(d))
        except AssertionError:  # a busy machine: say so, count what happened, go on
            unhealed = [UNHEALED]
    except AssertionError:
        return [UNHEALED]
    return false_since(d, mark) + unhealed


def restarts(tmp: Path, runs: int, say: Callable[[str], None]) -> list[list[str]]:
    system, key = fast_copy(tmp), key_file(tmp)
    b = RunningBoard(system, key_file=key)
    out: list[list[str]] = []
    try:
        d = daemon_on(tmp / "d0", b, system, key)
        try:
            d.wait_for(healthy, HEAL_S, "the robot up")
            for k in range(1, runs + 1):
                d.kill()
                d.close()
                wait_until(lambda: not node_processes(system), 60, "the nodes gone")
                d = daemon_on(tmp / f"d{k}", b, system, key)
                unhealed = []
                try:
                    d.wait_for(healthy, HEAL_S, "healthy after the restart")
                    d.settled(3.0)
                except AssertionError:
                    unhealed = [UNHEALED]
                out.append(false_since(d, 0, ("stop_node",)) + unhealed)
                say(f"restart {k}: {out[-1] or 'none'}")
        finally:
            d.close()
    finally:
        b.stop()
    return out


def run(cases: tuple[str, ...], runs: int, amps: float, noise_s: float,
        say: Callable[[str], None]) -> dict[str, list[list[str]]]:
    results: dict[str, list[list[str]]] = {}
    with tempfile.TemporaryDirectory(prefix="false-repairs-") as tmp_s:
        tmp = Path(tmp_s)
        shared = [c for c in cases if c != "restart"]
        if shared:
            (tmp / "shared").mkdir()
            with healthy_robot(tmp / "shared", HEAL_S) as d:
                for case in shared:
                    results[case] = []
                    for k in range(1, runs + 1):
                        got = one_run(d, case, amps, noise_s)
                        results[case].append(got)
                        say(f"{case} {k}: {got or 'none'}")
        if "restart" in cases:
            (tmp / "restart").mkdir()
            results["restart"] = restarts(tmp / "restart", runs, say)
    return results


def table(results: dict[str, list[list[str]]], amps: float) -> str:
    names = {"brownout": "brown-out (20 V, 3 s)", "freeze": "link freeze (5 s)",
             "restart": "kill -9 + restart", "noise": f"sensor noise (hokuyo, sd {amps:g} A)"}
    rows = ["| case | runs | runs with a false repair | false repairs | what | runs not "
            "healthy again in time |", "|---|---|---|---|---|---|"]
    for case, per_run in results.items():
        unhealed = sum(UNHEALED in r for r in per_run)
        real = [[a for a in r if a != UNHEALED] for r in per_run]
        seen = sorted({a for r in real for a in r})
        rows.append(f"| {names[case]} | {len(per_run)} | {sum(bool(r) for r in real)} | "
                    f"{sum(len(r) for r in real)} | {', '.join(seen) or '-'} | {unhealed} |")
    return "\n".join(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--cases", default=",".join(CASES),
                    help=f"comma-separated, of {', '.join(CASES)}")
    ap.add_argument("--noise-amps", type=float, default=1.0,
                    help="the noise's standard deviation in A (default 1.0)")
    ap.add_argument("--noise-s", type=float, default=10.0,
                    help="how long the noise lasts in each run (default 10 s)")
    ap.add_argument("--write", action="store_true", help="append to benchmarks/RESULTS.md")
    args = ap.parse_args()
    cases = tuple(c for c in args.cases.split(",") if c)
    bad = [c for c in cases if c not in CASES]
    if bad or args.runs < 1:
        print(f"false_repairs: --cases takes {', '.join(CASES)}; --runs at least 1 "
              f"(got {', '.join(bad) or args.runs})", file=sys.stderr)
        sys.exit(2)
    load0 = os.getloadavg()[0]
    t0 = time.monotonic()
    results = run(cases, args.runs, args.noise_amps, args.noise_s,
                  lambda line: print(line, flush=True))
    load1 = os.getloadavg()[0]
    text = table(results, args.noise_amps)
    print(text)
    print(f"load average {load0:.1f} at the start, {load1:.1f} at the end; "
          f"{time.monotonic() - t0:.0f} s")
    if args.write:
        with contextlib.suppress(OSError), (ROOT / "benchmarks" / "RESULTS.md").open("a") as f:
            f.write(f"\n### false repairs, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
                    f" (load average {load0:.1f} -> {load1:.1f})\n\n{text}\n")


if __name__ == "__main__":
    main()
