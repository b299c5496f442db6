"""Run the robot's mission on the emulated robot, with its world and the daemon.

``dxboard mission SYSTEM_DIR [--journal FILE] [--web H:P] [--fast] [--timeout S] [--flat]``
starts the robot's emulated board, devices and world (``dxboard emulate --robot --world``) and
the daemon, through ``host.launch``; waits until layer 0 has brought the robot up; then runs
the mission of ``SYSTEM_DIR/mission/mission.yaml`` with the layers of paper 001 (skills,
behaviour trees, the temporal planner and dispatcher: ``host.mission``). It prints a line as
each step that takes seconds begins (starting the robot, layer 0 bringing it up, starting the
layers, the mission), then one line per
event of the mission (planned, each dispatch, each result of layers 2 and 3, each change of the
knowledge base) and of layer 0 (diagnoses, repair plans and their ends, quarantines), and exits
0 when the mission completed, 1 when it stopped or failed (the last line says why, naming the
components to blame). Every event is in the journal (default: a temporary one, removed
afterwards); ``--web`` serves the daemon's page while it runs. ``--fast`` uses short device
boot times (for tests); ``--flat`` runs the baseline without the layers' hand-over.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

NAME = "mission"
HELP = "run the robot's mission (paper 001's layers) on the emulated robot and its world"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system_dir", metavar="SYSTEM_DIR", help="robot directory (models/NAME)")
    parser.add_argument("--journal", metavar="FILE",
                        help="journal file (default: a temporary one, removed afterwards)")
    parser.add_argument("--web", metavar="HOST:PORT", help="serve the daemon's page here")
    parser.add_argument("--fast", action="store_true",
                        help="short device boot times (for tests); default: the real devices'")
    parser.add_argument("--flat", action="store_true",
                        help="without the layers' hand-over (the baseline of mission-fault)")
    parser.add_argument("--timeout", type=float, default=300.0, metavar="S",
                        help="give up after S seconds (default 300)")


def run(args: argparse.Namespace) -> int:
    import asyncio
    import tempfile

    from host.commands.experiment import check_robot, journal_path
    from host.events import (
        DiagnosisRecord,
        Dispatch,
        KbChange,
        LayerResult,
        MissionState,
        PlanRecord,
        QuarantineChange,
        RepairEnded,
        Stamped,
        describe,
    )
    from host.experiment.mission import run_mission
    from host.experiment.robot import fast_model
    from host.mission.files import load_mission
    from host.web.server import parse_listen

    system_dir = check_robot(Path(args.system_dir), args.timeout)
    load_mission(system_dir)  # a mistake in the mission is one line before anything starts
    web = parse_listen(args.web) if args.web else None
    shown = (MissionState, Dispatch, KbChange, DiagnosisRecord, PlanRecord, RepairEnded,
             QuarantineChange)

    def show(s: Stamped) -> None:
        e = s.event
        if isinstance(e, shown) or (isinstance(e, LayerResult) and e.layer >= 2):
            stamp = time.strftime("%H:%M:%S", time.localtime(s.wall))
            print(f"{stamp} {describe(e)}", flush=True)

    def step(text: str) -> None:
        print(f"{time.strftime('%H:%M:%S')} {text}", flush=True)

    with tempfile.TemporaryDirectory(prefix="dxboard-mission-") as tmp:
        robot_dir = fast_model(system_dir, Path(tmp)) if args.fast else system_dir
        journal = journal_path(args.journal, Path(tmp))
        res = asyncio.run(run_mission(robot_dir, journal, flat=args.flat,
                                      timeout_s=args.timeout, web=web, on_event=show,
                                      on_step=step))
    verdict = "completed" if res.completed else "did not complete: " + res.detail
    print(f"mission {verdict} ({res.actions} actions, {res.replans} replans, "
          f"{res.duration_s or 0:.1f} s)")
    return 0 if res.completed else 1
