"""Run paper 000's experiments (§VI) on the virtual robot and report the times.

``dxboard experiment power-up SYSTEM_DIR`` starts the robot with everything off but the board
and the PC; the daemon diagnoses, plans and brings it up by itself. It runs twice, each time
on a freshly started robot: independent steps in parallel (the daemon's way), then one step
at a time. It reports the diagnosis the first plan was made on (the paper: all 11 components
abnormal; the robot's model adds the thermal camera and its driver, reported apart), the plan,
each action's start and end, and the time to all-normal from the daemon's start and from the
first action, next to the paper's 8.1 s -> 38.3 s = 30.2 s.

``dxboard experiment device-shutdown SYSTEM_DIR`` brings the robot up, then switches the base
(jaguar) off as an operator with the key would, and reports detection, diagnosis, plan(s),
each action and the time to all-normal again, counted from the switch-off (the paper's repair:
power_up, stop_node, start_node).

The daemon runs in this process on free ports, without a web page; the emulated board and
devices run as a child process and the nodes as processes, as with ``dxboard run --emulate``.
Options:

  --journal FILE   the journal (default: a temporary file, removed afterwards); the
                   power-up's one-at-a-time run goes to FILE-sequential.sqlite beside it.
                   Draw it with ``dxboard report FILE -o timeline.png --model SYSTEM_DIR``
  --json           the results as JSON (keys: see host/experiment/render.py)
  --fast           short device boot times (lidar 1.5 s, base and mount 0.3 s) instead of
                   the real devices' (lidar 5 s, base and mount 1 s), for tests
  --only parallel|sequential   power-up: one of the two runs
  --timeout S      give up a run after S seconds (default 180)
"""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "experiment"
HELP = "run paper 000's power-up or device shut-down experiment on the virtual robot"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("which", choices=("power-up", "device-shutdown"),
                        help="the experiment: power-up (§VI-A) or device-shutdown (§VI-B)")
    parser.add_argument("system_dir", metavar="SYSTEM_DIR", help="robot directory (models/NAME)")
    parser.add_argument("--journal", metavar="FILE",
                        help="journal file (default: a temporary one, removed afterwards)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--fast", action="store_true",
                        help="short device boot times (for tests); default: the real devices'")
    parser.add_argument("--only", choices=("parallel", "sequential"),
                        help="power-up: run only this execution mode (default: both)")
    parser.add_argument("--timeout", type=float, default=180.0, metavar="S",
                        help="give up a run after S seconds (default 180)")


def run(args: argparse.Namespace) -> int:
    import asyncio
    import json
    import tempfile

    from host.errors import UserError
    from host.experiment import device_shutdown, power_up
    from host.experiment.experiments import SHUTDOWN_DEVICE
    from host.experiment.render import (
        power_up_json,
        power_up_text,
        shutdown_json,
        shutdown_text,
    )
    from host.experiment.robot import fast_model

    system_dir = Path(args.system_dir)
    if not (system_dir / "system.yaml").is_file():
        raise UserError(f"{system_dir}: no system.yaml here",
                        "give a robot directory, e.g. models/tedusar")
    if not (system_dir / "robot.yaml").is_file():
        raise UserError(f"{system_dir}: no robot.yaml, so no virtual robot to experiment on",
                        "use a robot with virtual devices, e.g. models/tedusar")
    if args.timeout <= 0:
        raise UserError(f"--timeout {args.timeout:g} must be positive")
    if args.journal is not None:
        journal = Path(args.journal)
        if not journal.parent.is_dir():
            raise UserError(f"--journal {args.journal}: directory {journal.parent} does not "
                            "exist", "create it first")
        for j in (journal, _sequential(journal)):
            if j.exists():
                raise UserError(f"--journal: {j} exists already",
                                "give a new file name, or remove the old journal")
    with tempfile.TemporaryDirectory(prefix="dxboard-experiment-") as tmp:
        robot_dir = fast_model(system_dir, Path(tmp)) if args.fast else system_dir
        base = journal if args.journal is not None else Path(tmp) / "journal.sqlite"
        robot = system_dir.resolve().name
        if args.which == "power-up":
            modes = [args.only] if args.only else ["parallel", "sequential"]
            runs = {}
            for mode in modes:
                path = _sequential(base) if mode == "sequential" and len(modes) > 1 else base
                runs[mode] = asyncio.run(power_up(robot_dir, path,
                                                  sequential=mode == "sequential",
                                                  timeout_s=args.timeout))
            if args.json:
                print(json.dumps(power_up_json(robot, args.fast, runs), indent=2))
            else:
                print(power_up_text(robot, args.fast, runs))
        else:
            res = asyncio.run(device_shutdown(robot_dir, base, timeout_s=args.timeout))
            if args.json:
                print(json.dumps(shutdown_json(robot, args.fast, res, SHUTDOWN_DEVICE),
                                 indent=2))
            else:
                print(shutdown_text(robot, args.fast, res, SHUTDOWN_DEVICE))
    return 0


def _sequential(journal: Path) -> Path:
    p = journal
    return p.with_name(p.stem + "-sequential" + (p.suffix or ".sqlite"))
