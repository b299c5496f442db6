"""A full disk: how fast the robot heals while its disk is full, and the journal catches up.

Issue 25's "Done when" for item 4: the lidar hang healthy within 15 s of the fault while the
disk is full, the backlog journalled within 5 s of space returning, 0 entries lost. Each run is
``benchmarks._rigs.disk.full_disk_run``: a real ``dxboard run --emulate`` (Zenoh) with its
journal and node logs on a 3 MB tmpfs this benchmark mounts (it must run as root), the disk
filled once the robot is healthy, ``hokuyo hang`` injected, the space freed once the robot is
healthy again, every entry the daemon says it recorded looked for in the journal. There is no
baseline: before this change the repair never ended (``stop_node(hokuyo_node) started`` for
good, tests/daemon/test_full_disk.py run on the old code).

    .venv/bin/python -m benchmarks.disk [--runs N] [--write]
    .venv/bin/python benchmarks/disk.py ...

It prints the figures; ``--write`` appends them as a section, with the date and the load
average, to benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# as a script, benchmarks/ comes first on the path, and its protocol.py would hide the package
sys.path[:] = [str(ROOT), *(p for p in sys.path
                            if Path(p or ".").resolve() not in (ROOT, ROOT / "benchmarks"))]

from benchmarks._rigs.disk import FullDiskRun, full_disk_run  # noqa: E402

HEAL_GOAL_S = 15.0
JOURNAL_GOAL_S = 5.0


def section(runs: list[FullDiskRun], argv: str, load_before: str, load_after: str) -> list[str]:
    heal = [r.fault_to_healthy_s for r in runs]
    catch = [r.free_to_journalled_s for r in runs]
    lost = sum(r.lost for r in runs)
    recorded = sum(r.recorded for r in runs)
    ok = sum(1 for r in runs if r.fault_to_healthy_s <= HEAL_GOAL_S
             and r.free_to_journalled_s <= JOURNAL_GOAL_S and r.lost == 0)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    lines = [
        "## A full disk (journal and node logs on a full 3 MB tmpfs)",
        "",
        f"`{argv}`, {stamp}, load average {load_before} before and {load_after} after "
        "(1/5/15 min) on the 2 cores.",
        "",
        f"Lidar hang → healthy with the disk full: worst **{max(heal):.1f} s** "
        f"(goal ≤ {HEAL_GOAL_S:g} s); space back → backlog journalled: worst "
        f"**{max(catch):.2f} s** (goal ≤ {JOURNAL_GOAL_S:g} s); entries lost: **{lost}** of "
        f"{recorded} recorded (goal 0); {ok}/{len(runs)} runs meet all three. No baseline: "
        "on main the repair never ended (`stop_node(hokuyo_node) started` for good).",
        "",
        "| run | hang → healthy | space → journalled | held when freed | recorded | lost "
        "| dropped |",
        "|---|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(runs, 1):
        lines.append(f"| {i} | {r.fault_to_healthy_s:.1f} s | {r.free_to_journalled_s:.2f} s "
                     f"| {r.held_at_free} | {r.recorded} | {r.lost} | {r.dropped} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="full-disk runs (default 3)")
    ap.add_argument("--write", action="store_true", help="append to benchmarks/RESULTS.md")
    args = ap.parse_args()
    if args.runs < 1:
        print(f"benchmarks/disk.py: --runs {args.runs}: give 1 or more", file=sys.stderr)
        sys.exit(2)
    if os.geteuid() != 0:
        print("benchmarks/disk.py: mounting the small disk needs root: run it as root",
              file=sys.stderr)
        sys.exit(2)

    def load() -> str:
        return "/".join(f"{x:.1f}" for x in os.getloadavg())

    before = load()
    runs = []
    for i in range(args.runs):
        with tempfile.TemporaryDirectory(prefix="dxboard-disk-") as tmp:
            run = full_disk_run(Path(tmp))
        print(f"run {i + 1}: hang -> healthy {run.fault_to_healthy_s:.1f} s, space -> "
              f"journalled {run.free_to_journalled_s:.2f} s, lost {run.lost} of "
              f"{run.recorded}", flush=True)
        runs.append(run)
    argv = " ".join(["python -m benchmarks.disk", *sys.argv[1:]])
    text = section(runs, argv.replace(" --write", ""), before, load())
    print("\n".join(text))
    if args.write:
        path = ROOT / "benchmarks" / "RESULTS.md"
        path.write_text(path.read_text().rstrip("\n") + "\n\n" + "\n".join(text) + "\n")


if __name__ == "__main__":
    main()
