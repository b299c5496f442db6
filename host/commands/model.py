"""Check a robot model and show the clauses generated from it.

``dxboard model check SYSTEM_DIR`` validates ``system.yaml`` and the observation files in
``SYSTEM_DIR/scenarios/*.obs`` (every literal must be one the clauses mention) and prints each
problem as ``file:line: message (fix)``; exit code 0 when valid, 1 when not. ``dxboard model clauses
SYSTEM_DIR`` prints the generated clauses, one rule a line, grouped by the paper's clause
number (a tug model file is accepted too).
"""

from __future__ import annotations

import argparse
import sys

NAME = "model"
HELP = "check a robot model (system.yaml) or print its generated clauses"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("action", choices=["check", "clauses"], help="what to do")
    parser.add_argument("system_dir", metavar="SYSTEM_DIR",
                        help="robot directory holding system.yaml")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from host.diagnosis.files import load_theory, read_observations
    from host.diagnosis.generate import generate
    from host.diagnosis.logic import format_clauses
    from host.diagnosis.model import check_system, load_system
    from host.errors import UserError

    if args.action == "check":
        problems = check_system(args.system_dir)
        for problem in problems:
            print(problem, file=sys.stderr)
        if problems:
            print(f"{len(problems)} problem(s)", file=sys.stderr)
            return 1
        model = load_system(args.system_dir)
        theory = generate(model)
        scenarios = sorted((Path(args.system_dir) / "scenarios").glob("*.obs"))
        bad = 0
        for obs_file in scenarios:
            try:
                read_observations(obs_file, theory)
            except UserError as exc:
                print(exc, file=sys.stderr)
                bad += 1
        if bad:
            print(f"{bad} problem(s)", file=sys.stderr)
            return 1
        print(f"{model.path}: ok ({len(model.components)} components, "
              f"{len(model.topics())} topics, {len(theory.clauses)} clauses, "
              f"{len(scenarios)} scenario file(s))")
        return 0
    sys.stdout.write(format_clauses(load_theory(args.system_dir)))
    return 0
