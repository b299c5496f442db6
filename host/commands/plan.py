"""Offline repair planning: a diagnosis in, a partially ordered repair plan out.

``dxboard plan SYSTEM_DIR --bad A,B [--bad C ...] [--diagnoses FILE] [--obs FILE]
[--planner NAME] [--domain FILE] [--write-problem FILE] [--json]``. SYSTEM_DIR holds
system.yaml and repair.pddl. Each ``--bad`` is one diagnosis (the components it finds
abnormal); ``--diagnoses`` reads the JSON of ``dxboard diagnose --json``. With several
diagnoses the policy picks one (or all at once) and prints why. ``--obs`` holds observations,
one literal a line (``~on(jaguar)``, ``running(jaguar_node)``); what is not observed is
assumed and listed. Nothing is switched: planning is a dry run. ``--json`` prints ``{"plan":
[{"id": 0, "action": "power_up", "args": ["jaguar"], "after": []}, ...], "layers": ...,
"strategy": ..., "reason": ...}``; ``after`` lists the steps that must finish first.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from host.diagnosis.logic import Literal
    from host.repair.policy import Candidate

NAME = "plan"
HELP = "plan a repair offline: diagnosis -> partially ordered repair plan"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system", metavar="SYSTEM_DIR", help="robot directory (system.yaml)")
    parser.add_argument("--bad", action="append", default=[], metavar="A,B",
                        help="a diagnosis: abnormal components, comma-separated (repeatable)")
    parser.add_argument("--diagnoses", metavar="FILE",
                        help="diagnoses as printed by `dxboard diagnose --json`")
    parser.add_argument("--obs", metavar="FILE", help="observations, one literal a line")
    parser.add_argument("--planner", default="astar",
                        help="astar (default), bfs or fast-downward")
    parser.add_argument("--domain", metavar="FILE",
                        help="repair domain (default: SYSTEM_DIR/repair.pddl)")
    parser.add_argument("--write-problem", metavar="FILE",
                        help="also write the PDDL problem of the chosen diagnosis")
    parser.add_argument("--json", action="store_true", help="print JSON")


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.repair.errors import PlanningLimitError
    from host.repair.planner import PLANNERS, RepairPlanner
    from host.repair.policy import choose
    from host.repair.problem import to_pddl

    if args.planner not in PLANNERS:
        raise UserError(f"unknown planner {args.planner!r}",
                        f"use one of {', '.join(sorted(PLANNERS))}")
    planner = RepairPlanner.for_system(args.system, args.domain)
    observations = read_observations(args.obs) if args.obs else []
    candidates = _candidates(args, planner.model.types)
    try:
        choice = choose(planner, candidates, observations, planner_name=args.planner)
    except PlanningLimitError as exc:
        raise UserError(str(exc), "try --planner fast-downward, or repair fewer at once") from exc
    if args.write_problem:
        problem = planner.problem(choice.bad, observations)
        Path(args.write_problem).write_text(to_pddl(problem, planner.domain.name))
    if args.json:
        print(json.dumps(choice.to_json(), indent=2))
        return 0
    if not choice.plan.steps:
        print("nothing to do: " + choice.reason if choice.strategy == "none" else "empty plan")
        return 0
    print(f"repair {', '.join(sorted(choice.bad))} ({choice.strategy}: {choice.reason})")
    for s in choice.plan.steps:
        after = choice.plan.after[s.id]
        wait = f"   after {', '.join(str(i + 1) for i in sorted(after))}" if after else ""
        print(f"{s.id + 1:3d}. {s}{wait}")
    for note in choice.plan.notes:
        print(f"note: {note}")
    return 0


def _candidates(args: argparse.Namespace, known: Any) -> list[Candidate]:
    from host.diagnosis.model import load_system
    from host.errors import UserError
    from host.repair.policy import Candidate, prior_weight

    out: list[Candidate] = []
    if args.diagnoses:
        out += read_diagnoses(args.diagnoses)
    if args.bad:
        system = load_system(args.system)
        priors = {c.name: c.prior for c in system.components.values() if c.prior is not None}
        for text in args.bad:
            bad = frozenset(x.strip() for x in text.split(",") if x.strip())
            out.append(Candidate(bad, prior_weight(bad, priors)))
    if not out:
        raise UserError("no diagnosis given", "pass --bad A,B or --diagnoses FILE")
    for c in out:
        unknown = sorted(c.bad - set(known))
        if unknown:
            raise UserError(
                f"unknown component(s) {', '.join(unknown)} in the diagnosis",
                f"use names from {args.system}/system.yaml",
            )
    return out


def read_observations(path: str) -> list[Literal]:
    """One literal a line; blank lines and ``#`` comments are skipped."""
    from host.diagnosis.logic import parse_literal
    from host.errors import UserError

    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise UserError(f"{path}: cannot read the observations ({exc.strerror})",
                        "give a file with one literal a line") from exc
    out = []
    for n, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        try:
            out.append(parse_literal(line))
        except ValueError as exc:
            raise UserError(f"{path}:{n}: {exc}",
                            "write one literal a line, like ~on(jaguar)") from exc
    return out


def read_diagnoses(path: str) -> list[Candidate]:
    """The ``diagnoses`` of ``dxboard diagnose --json``."""
    from host.errors import UserError
    from host.repair.policy import Candidate

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        items = data["diagnoses"] if isinstance(data, dict) else data
        return [Candidate(frozenset(d["bad"]), float(d.get("probability", 0.0)))
                for d in items]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise UserError(
            f"{path}: not a diagnoses file ({exc})",
            'write the output of `dxboard diagnose --json`: {"diagnoses": [{"bad": [...]}]}',
        ) from exc
