"""Run paper 000's experiments (§VI) and the missions' (M1-M4) on the virtual robot.

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

``dxboard experiment mission-fault SYSTEM_DIR`` is M1 of the missions (MISSIONS.md, paper 001):
the robot's mission (``dxboard mission``) three times, each on a freshly started robot with its
world: fault-free; with the Hokuyo hanging during the first navigation, the layered robot
(layer 0 repairs it while the behaviour tree's guard holds the navigation, the mission layer
never sees a failure); and the same fault on the flat system (the skill aborts once its inputs stop,
the action fails, the mission replans). It reports each run's duration, actions, replans, the
fault and layer 0's repair, the failures that reached the mission layer, and the delays
against the fault-free run. The journals (``--journal FILE``: FILE for the layered run,
FILE-fault-free.sqlite and FILE-flat.sqlite beside it) draw as timelines with ``dxboard
report``.

``dxboard experiment door-closed|marker-missing|plan-error SYSTEM_DIR`` are M2-M4 (MISSIONS.md,
paper 004's plan-execution diagnosis): the mission fault-free, then with an event injected
through the arena (``host.experiment.plandiag``): M2 a door falls shut behind the robot (an
exogenous event, found at the precondition check of the way out; the new plan opens it); M3 the
marker dispenser jams (a local action fault; the victim is marked again); M4 a locked door the
domain's open_door ignores (a plan error naming the condition the domain lacks). Each reports
the diagnosis (class, symptoms, fault region, alternative histories, the winning path of the
context tree, the corrected knowledge base or the plan error), the new plan, the time from the
alarm to the diagnosis and to the new plan, and the mission's delay against the fault-free run
(its journal: FILE-fault-free.sqlite beside FILE).

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
  --no-fault-free  M1-M4: leave out the fault-free run (and the delays against it), when a
                   fault-free run of the same mission was made already
  --timeout S      give up a run after S seconds (default 180)
"""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "experiment"
HELP = ("run paper 000's power-up or device shut-down experiment, or a mission experiment "
        "(M1 mission-fault, M2-M4 plan-execution diagnosis), on the virtual robot")
PLANDIAG = ("door-closed", "marker-missing", "plan-error")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("which", choices=("power-up", "device-shutdown", "mission-fault",
                                          *PLANDIAG),
                        help="the experiment: power-up (§VI-A), device-shutdown (§VI-B), "
                             "mission-fault (MISSIONS.md's M1), door-closed (M2), "
                             "marker-missing (M3) or plan-error (M4)")
    parser.add_argument("system_dir", metavar="SYSTEM_DIR", help="robot directory (models/NAME)")
    parser.add_argument("--journal", metavar="FILE",
                        help="journal file (default: a temporary one, removed afterwards)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--fast", action="store_true",
                        help="short device boot times (for tests); default: the real devices'")
    parser.add_argument("--only", choices=("parallel", "sequential"),
                        help="power-up: run only this execution mode (default: both)")
    parser.add_argument("--no-fault-free", dest="fault_free", action="store_false",
                        help="M1-M4: leave out the fault-free run (and the delays against it)")
    parser.add_argument("--timeout", type=float, default=180.0, metavar="S",
                        help="give up a run after S seconds (default 180)")


def run(args: argparse.Namespace) -> int:
    import asyncio
    import json
    import tempfile

    from host.experiment import device_shutdown, power_up
    from host.experiment.experiments import SHUTDOWN_DEVICE
    from host.experiment.render import (
        power_up_json,
        power_up_text,
        shutdown_json,
        shutdown_text,
    )
    from host.experiment.robot import fast_model
    from host.experiment.session import beside

    system_dir = check_robot(Path(args.system_dir), args.timeout)
    if not args.fault_free and args.which not in ("mission-fault", *PLANDIAG):
        from host.errors import UserError

        raise UserError(f"--no-fault-free: {args.which} has no fault-free run",
                        "use it with mission-fault, door-closed, marker-missing or plan-error")
    if args.journal is not None:
        journal = Path(args.journal)
        _check_new(journal)
        if args.which == "power-up":
            _check_new(beside(journal, "sequential"))
        if args.which == "mission-fault":
            _check_new(beside(journal, "flat"))
        if args.which in ("mission-fault", *PLANDIAG) and args.fault_free:
            _check_new(beside(journal, "fault-free"))
    with tempfile.TemporaryDirectory(prefix="dxboard-experiment-") as tmp:
        robot_dir = fast_model(system_dir, Path(tmp)) if args.fast else system_dir
        base = journal if args.journal is not None else Path(tmp) / "journal.sqlite"
        robot = system_dir.resolve().name
        if args.which in PLANDIAG:
            from host.experiment.plandiag import plan_diagnosis, plan_diagnosis_text

            pd = asyncio.run(plan_diagnosis(args.which, robot_dir, base,
                                            timeout_s=args.timeout, fault_free=args.fault_free))
            if args.json:
                print(json.dumps({"experiment": args.which, "robot": robot, "fast": args.fast,
                                  "runs": {k: r.to_json() for k, r in pd.items()}}, indent=2))
            else:
                print(plan_diagnosis_text(args.which, robot, args.fast, pd))
        elif args.which == "mission-fault":
            from host.experiment.mission import mission_fault, mission_fault_text

            m1 = asyncio.run(mission_fault(robot_dir, base, timeout_s=args.timeout,
                                           fault_free=args.fault_free))
            if args.json:
                print(json.dumps({"experiment": "mission-fault", "robot": robot,
                                  "fast": args.fast,
                                  "runs": {k: r.to_json() for k, r in m1.items()}}, indent=2))
            else:
                print(mission_fault_text(robot, args.fast, m1))
        elif args.which == "power-up":
            modes = [args.only] if args.only else ["parallel", "sequential"]
            runs = {}
            for mode in modes:
                second = mode == "sequential" and len(modes) > 1
                path = beside(base, "sequential") if second else base
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


def check_robot(system_dir: Path, timeout: float) -> Path:
    """A robot directory with virtual devices, and a positive timeout; else one clear line."""
    from host.errors import UserError

    if not (system_dir / "system.yaml").is_file():
        raise UserError(f"{system_dir}: no system.yaml here",
                        "give a robot directory, e.g. models/tedusar")
    if not (system_dir / "robot.yaml").is_file():
        raise UserError(f"{system_dir}: no robot.yaml, so no virtual robot to experiment on",
                        "use a robot with virtual devices, e.g. models/tedusar")
    if timeout <= 0:
        raise UserError(f"--timeout {timeout:g} must be positive")
    return system_dir


def _check_new(journal: Path) -> None:
    from host.errors import UserError

    if not journal.parent.is_dir():
        raise UserError(f"--journal {journal}: directory {journal.parent} does not exist",
                        "create it first")
    if journal.exists():
        raise UserError(f"--journal: {journal} exists already",
                        "give a new file name, or remove the old journal")


def journal_path(arg: str | None, tmp: Path) -> Path:
    """``--journal`` checked (a new file in an existing directory), or one in ``tmp``."""
    if arg is None:
        return tmp / "journal.sqlite"
    _check_new(Path(arg))
    return Path(arg)


