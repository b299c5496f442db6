"""Stops under stress: signals under a message flood, and daemons on hostile boards.

Two measurements of issue 25's "Done when":

1. **Signals under a flood.** ``benchmarks._rigs.flood_child`` runs the daemon's real zenoh topic
   source fed 2,000 messages a second by a real zenoh publisher, holds its event loop up for
   2 s and sends itself SIGINT 1.5 s into the stall. A run counts when the loop hears the signal
   within 10 s of it. ``--runs`` runs (default 100) with the daemon's signal handling
   (``host.launch.signals``); the baseline, in the same run, is ``--baseline-runs`` runs
   (default 10) with asyncio's ``add_signal_handler`` on its shared self-pipe, as ``dxboard
   run`` had before.
2. **Hostile boards x stop.** ``dxboard run --board URL`` against each kind of hostile board of
   ``benchmarks._rigs.hostile`` (silent, garbage, flood, half-open, slow drip, reset mid-frame,
   accept-and-close, never-accepting, echo, refused) and a real emulated board holding another
   key (wrong key): 11 kinds. The daemon meets the board for 8 s, gets SIGTERM, and counts when
   it has exited within 10 s; the table says how long each took, its exit code and the stages
   its stop cut short.

    .venv/bin/python -m benchmarks.stops [--runs N] [--baseline-runs N] [--write]
    .venv/bin/python benchmarks/stops.py ...

It prints the figures; ``--write`` appends them as a section, with the date and the load
average, to benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks._rigs.hostile import KINDS, HostileBoard  # noqa: E402
from benchmarks._rigs.robots import KEY  # noqa: E402
from benchmarks._rigs.stopper import StoppedRun  # noqa: E402
from host.launch.boards import RunningBoard  # noqa: E402
from host.launch.ports import zenoh_endpoint  # noqa: E402
from host.launch.running import TEDUSAR  # noqa: E402

WITHIN_S = 10.0
RATE = 2000
STALL_S = 2.0
HEARD = re.compile(r"heard SIGINT after (-?[\d.]+) s")


def flood_run(baseline: bool) -> float | None:
    """One flood run: seconds from SIGINT to the loop hearing it, or None (lost)."""
    argv = [sys.executable, "-m", "benchmarks._rigs.flood_child", zenoh_endpoint(), str(RATE),
            str(STALL_S), *(["--asyncio"] if baseline else [])]
    try:
        out = subprocess.run(argv, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                             capture_output=True, text=True,
                             timeout=120)
    except subprocess.TimeoutExpired:
        return None
    m = HEARD.search(out.stdout)
    return float(m.group(1)) if m else None


def flood(runs: int, baseline: bool) -> tuple[int, list[float]]:
    """(runs heard within WITHIN_S, the delays of those heard)."""
    delays = []
    for i in range(runs):
        d = flood_run(baseline)
        if d is not None:
            delays.append(d)
        print(f"  flood {'baseline ' if baseline else ''}{i + 1}/{runs}: "
              f"{'LOST' if d is None else f'{d:.2f} s'}", flush=True)
    return sum(1 for d in delays if d <= WITHIN_S), delays


def hostile(tmp: Path) -> list[tuple[str, StoppedRun]]:
    out = []
    for kind in KINDS:
        (tmp / kind).mkdir()
        with HostileBoard(kind) as board:
            run = StoppedRun.against(board.url, tmp / kind, give_up_s=60)
        out.append((kind, run))
        print(f"  {kind}: {run.seconds:.1f} s, exit {run.code}", flush=True)
    emu = RunningBoard(TEDUSAR, key=KEY, robot=False)
    (tmp / "wrong_key").mkdir()
    try:
        run = StoppedRun.against(emu.urls["board"], tmp / "wrong_key", key_hex="ff" * 16,
                                 give_up_s=60)
    finally:
        emu.stop()
    out.append(("wrong_key", run))
    print(f"  wrong_key: {run.seconds:.1f} s, exit {run.code}", flush=True)
    return out


def cut(run: StoppedRun) -> str:
    stages = [x.split("stop: ", 1)[1].split(" did not close")[0] for x in run.lines
              if "did not close within" in x and "stop: " in x]
    return ", ".join(stages) or "-"


def section(runs: int, heard: int, delays: list[float], base_runs: int, base_heard: int,
            boards: list[tuple[str, StoppedRun]]) -> list[str]:
    load = "/".join(f"{x:.1f}" for x in os.getloadavg())
    ok = sum(1 for _, r in boards if r.code != -999 and r.seconds <= WITHIN_S)
    worst = max((d for d in delays), default=float("nan"))
    rows = [f"| {k} | {r.seconds:.1f} s | {'never' if r.code == -999 else r.code} | {cut(r)} |"
            for k, r in boards]
    return [
        "## Stops under stress (signals under a flood, hostile boards)",
        "",
        f"`.venv/bin/python -m benchmarks.stops --runs {runs} --baseline-runs {base_runs}`, "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average {load} "
        "(1/5/15 min) on the 2 cores.",
        "",
        f"Signals under a {RATE} msg/s zenoh flood with the loop stalled {STALL_S:g} s: "
        f"**{heard}/{runs}** SIGINTs heard within {WITHIN_S:g} s with `host.launch.signals` "
        f"(slowest {worst:.2f} s after the signal); baseline, asyncio's `add_signal_handler` "
        f"as before: **{base_heard}/{base_runs}**.",
        "",
        f"Hostile boards x SIGTERM after 8 s: **{ok}/{len(boards)}** stopped within "
        f"{WITHIN_S:g} s.",
        "",
        "| board | SIGTERM → exit | exit code | stages cut short |",
        "|---|---|---|---|",
        *rows,
        "",
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--runs", type=int, default=100, help="flood runs (default 100)")
    ap.add_argument("--baseline-runs", type=int, default=10,
                    help="flood runs with asyncio's signal handling (default 10)")
    ap.add_argument("--no-boards", action="store_true", help="skip the hostile boards")
    ap.add_argument("--write", action="store_true", help="append to benchmarks/RESULTS.md")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        boards = [] if args.no_boards else hostile(Path(tmp))
    print(f"signals under a {RATE} msg/s flood, loop stalled {STALL_S:g} s:", flush=True)
    heard, delays = flood(args.runs, baseline=False)
    base_heard, _ = flood(args.baseline_runs, baseline=True)
    text = section(args.runs, heard, delays, args.baseline_runs, base_heard, boards)
    print("\n".join(text))
    if args.write:
        path = ROOT / "benchmarks" / "RESULTS.md"
        path.write_text(path.read_text().rstrip("\n") + "\n\n" + "\n".join(text))


if __name__ == "__main__":
    main()
