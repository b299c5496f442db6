"""Check a robot model and show the clauses generated from it.

``dxboard model check MODEL`` validates a robot directory: ``system.yaml``, the observation
files in ``MODEL/scenarios/*.obs`` (every literal must be one the clauses mention) and the
repair domain ``MODEL/repair.pddl`` (parsed, and grounded over the robot's components, as the
planner will). It prints each problem as ``file:line: message (fix)``; exit code 0 when valid,
1 when not. A tug model file (the original system's format) is checked by loading it.
``dxboard model clauses MODEL`` prints the generated clauses, one rule a line, grouped by the
paper's clause number (a tug model file is accepted too). What a person should know about how
a model was read (a tug file's atoms missing from ``props``, say) is printed once on stderr as
``note: ...``.

``dxboard model learn OUT_DIR`` watches the running robot (ROS 2, or Zenoh with ``--middleware
zenoh``: ``--zenoh ENDPOINT`` and ``--zenoh-auth FILE``; ``--duration`` seconds,
60 by default; ``--board HOST:PORT`` also reads its board's currents, ``--probe`` then
switches each unprotected channel off in turn for at most 2 s) or reads a bag (``--bag BAG``,
on the bag's clock) and writes ``OUT_DIR/system.yaml`` for a person to review, every learned
item with its evidence (``host.learn``); progress lines go to stderr. ``dxboard model diff
OLD NEW`` prints what changed between two models, one line each; exit 0 when they are the
same, 1 when they differ, 2 on bad input (as ``diff`` does).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from host.diagnosis.logic import Theory

NAME = "model"
HELP = "check a robot model (system.yaml, scenarios, repair.pddl) or print its clauses"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    sub.required = True
    for name, what in (("check", "check a model (system.yaml, scenarios, repair.pddl)"),
                       ("clauses", "print the clauses generated from a model")):
        p = sub.add_parser(name, help=what)
        p.add_argument("system_dir", metavar="MODEL",
                       help="robot directory holding system.yaml, or a tug model file")
    p = sub.add_parser("learn", help="learn a model from the running robot or a bag "
                       "(writes OUT_DIR/system.yaml to review)")
    p.add_argument("out_dir", metavar="OUT_DIR", help="directory to write system.yaml into "
                   "(created; must not hold a system.yaml)")
    p.add_argument("--middleware", choices=["ros2", "zenoh"], default="ros2",
                   help="how to watch the robot (default ros2)")
    p.add_argument("--zenoh", metavar="ENDPOINT", action="append", default=[],
                   help="with --middleware zenoh: the robot's endpoint to connect to (default "
                   "tcp/127.0.0.1:7447, the one `dxboard run` listens on)")
    p.add_argument("--zenoh-auth", metavar="FILE",
                   help="with --middleware zenoh: the daemon's credentials file (JOURNAL-"
                   "zenoh.auth beside its journal; default $DXBOARD_ZENOH_AUTH)")
    p.add_argument("--duration", type=float, default=60.0, metavar="S",
                   help="seconds to watch (default 60)")
    p.add_argument("--board", metavar="HOST:PORT", help="also read this board's currents")
    p.add_argument("--key-file", metavar="FILE",
                   help="the board's key as hex, for --probe (else $DXBOARD_KEY)")
    p.add_argument("--bag", metavar="BAG", help="learn from this rosbag2 bag instead")
    p.add_argument("--probe", action="store_true", help="switch each unprotected channel off "
                   "in turn (at most 2 s) to learn which device feeds which node")
    p = sub.add_parser("diff", help="what changed between two models (exit 0 same, 1 differ)")
    p.add_argument("old", metavar="OLD", help="robot directory or system.yaml")
    p.add_argument("new", metavar="NEW", help="robot directory or system.yaml")


def print_notes(theory: Theory) -> None:
    for note in theory.notes:
        print(f"note: {note}", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    if args.action == "learn":
        return _learn(args)
    if args.action == "diff":
        return _diff(args)
    from host.diagnosis.files import load_theory
    from host.diagnosis.logic import format_clauses

    path = Path(args.system_dir)
    if args.action == "check" and path.is_dir():
        return _check_robot(path)
    theory = load_theory(path)
    print_notes(theory)
    if args.action == "check":
        print(f"{path}: ok ({len(theory.components)} components, "
              f"{len(theory.observable_atoms())} observable atoms, {len(theory.clauses)} "
              "clauses)")
        return 0
    sys.stdout.write(format_clauses(theory))
    return 0


def _check_robot(path: Path) -> int:
    from host.diagnosis.files import read_observations
    from host.diagnosis.generation import generate
    from host.diagnosis.model import check_system, load_system
    from host.errors import UserError
    from host.planning.domain import domain_file
    from host.repair.planner import RepairPlanner

    problems = check_system(path)
    for problem in problems:
        print(problem, file=sys.stderr)
    if problems:
        print(f"{len(problems)} problem(s)", file=sys.stderr)
        return 1
    model = load_system(path)
    theory = generate(model)
    scenarios = sorted((path / "scenarios").glob("*.obs"))
    bad = 0
    for obs_file in scenarios:
        try:
            read_observations(obs_file, theory)
        except UserError as exc:
            print(exc, file=sys.stderr)
            bad += 1
    domain = domain_file(path)
    checked = ""
    if domain.exists():
        try:
            task = RepairPlanner.for_system(path).task
            checked = f", {domain.name}: {len(task.ops)} ground actions"
        except UserError as exc:
            print(exc, file=sys.stderr)
            bad += 1
    if bad:
        print(f"{bad} problem(s)", file=sys.stderr)
        return 1
    print(f"{model.path}: ok ({len(model.components)} components, "
          f"{len(model.topics())} topics, {len(theory.clauses)} clauses, "
          f"{len(scenarios)} scenario file(s){checked})")
    return 0


def _say(line: str) -> None:
    print(f"dxboard model learn: {line}", file=sys.stderr, flush=True)


def _zenoh_auth(args: argparse.Namespace) -> Path | None:
    """The Zenoh credentials file: ``--zenoh-auth``, else ``$DXBOARD_ZENOH_AUTH``, checked."""
    import os

    from host.observers.sources.zenoh_auth import ENV, read

    given = args.zenoh_auth or os.environ.get(ENV)
    if args.middleware != "zenoh" or not given:
        return None
    read(Path(given))  # a file that is not one user:password line: one line, exit 2
    return Path(given)


def _learn(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.learn.infer import infer
    from host.learn.render import render
    from host.learn.session import LearnOptions, board_url, check_written

    out = Path(args.out_dir)
    if (out / "system.yaml").exists() or (out.exists() and not out.is_dir()):
        raise UserError(f"{out} holds a model already", "give a new directory for the model")
    if args.middleware == "zenoh" and args.bag:
        raise UserError("--bag learns from a ROS 2 bag, not over zenoh",
                        "leave out --middleware zenoh with --bag")
    if args.bag:
        if args.board or args.probe:
            raise UserError("--bag learns from the bag alone",
                            "leave out --board and --probe with --bag")
        from host.learn.bagsource import read_bag

        rec = read_bag(Path(args.bag))
        _say(f"read the bag {args.bag}: {sum(map(len, rec.arrivals.values()))} messages "
             f"of {len(rec.arrivals)} topics over {rec.end - rec.start:.1f} s")
    else:
        from host.board.keys import load_key
        from host.learn.session import learn_live

        url = board_url(args.board) if args.board else None
        key = load_key(args.key_file) if args.probe else None
        rec = learn_live(LearnOptions(args.duration, url, key, args.probe,
                                      middleware=args.middleware, zenoh=tuple(args.zenoh),
                                      auth=_zenoh_auth(args)), _say)
    model = infer(rec, out.resolve().name or "robot",
                  ros2=not args.bag and args.middleware == "ros2")
    out.mkdir(parents=True, exist_ok=True)
    (out / "system.yaml").write_text(render(model))
    problems = check_written(out)
    for problem in problems:
        print(problem, file=sys.stderr)
    managed = sum(1 for n in model.nodes if n.managed)
    observed = sum(1 for t in model.topics if t.proposal)
    print(f"{out / 'system.yaml'}: {len(model.nodes)} nodes ({managed} managed), "
          f"{len(model.topics)} topics ({observed} with a rate observer), "
          f"{len(model.devices)} devices; review it, then `dxboard model check {out}`")
    return 1 if problems else 0


def _diff(args: argparse.Namespace) -> int:
    from host.learn.diff import diff_models

    lines = diff_models(Path(args.old), Path(args.new))
    for line in lines:
        print(line)
    return 1 if lines else 0
