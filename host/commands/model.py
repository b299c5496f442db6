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
    parser.add_argument("action", choices=["check", "clauses"], help="what to do")
    parser.add_argument("system_dir", metavar="MODEL",
                        help="robot directory holding system.yaml, or a tug model file")


def print_notes(theory: Theory) -> None:
    for note in theory.notes:
        print(f"note: {note}", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
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
