"""Offline repair planning: a diagnosis in, a partially ordered repair plan out.

``dxboard plan MODEL --bad A,B [--bad C ...] [--diagnoses FILE] [--obs FILE] [--planner NAME]
[--domain FILE] [--middleware zenoh|ros2] [--write-problem FILE] [--json]``. MODEL is a robot
directory (system.yaml and repair.pddl) or a tug model file of the original system (its
components' kinds and dependencies read off the clauses; the domain is ``--domain`` or the
repair.pddl beside it). Any domain plans whose words for abnormal / healthy / powered / running
are declared or follow the original's conventions (``bad``/``good``/``not_on``: see
host/planning/vocabulary.py). Each ``--bad`` is one diagnosis (the components it finds abnormal);
``--diagnoses`` reads the JSON of ``dxboard diagnose --json``. With several diagnoses the policy
picks one (or all at once) and prints why. ``--obs`` holds observations in the format of
``dxboard diagnose`` (``~on(jaguar)``, ``running(jaguar_node)``); a literal the model does not
know is an error; what is not observed is assumed and listed. The robot's middleware decides, as
for the daemon, whether a managed (``lifecycle: true``) node is repaired by ``reconfigure_node``
(ROS 2) or restarted (Zenoh): ``--middleware``, else ``$DXBOARD_MIDDLEWARE``, else the robot's
``observers: source: kind:`` (robot directories only).
``dxboard plan --problem FILE --domain FILE`` plans a PDDL problem file as it is (the original
repair server's). Nothing is switched: planning is a dry run. ``--json`` prints ``{"plan":
[{"id": 0, "action": "power_up", "args": ["jaguar"], "after": []}, ...], "layers": ...,
"strategy": ..., "reason": ...}``; ``after`` lists the steps that must finish first.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from host.planning.plan import Plan
    from host.repair.policy import Candidate

NAME = "plan"
HELP = "plan a repair offline: diagnosis -> partially ordered repair plan"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system", metavar="MODEL", nargs="?",
                        help="robot directory (system.yaml, repair.pddl) or tug model file")
    parser.add_argument("--bad", action="append", default=[], metavar="A,B",
                        help="a diagnosis: abnormal components, comma-separated (repeatable)")
    parser.add_argument("--diagnoses", metavar="FILE",
                        help="diagnoses as printed by `dxboard diagnose --json`")
    parser.add_argument("--obs", metavar="FILE",
                        help="observations, one literal a line (as for dxboard diagnose)")
    parser.add_argument("--planner", default="astar",
                        help="astar (default), bfs or fast-downward")
    parser.add_argument("--domain", metavar="FILE",
                        help="repair domain (default: MODEL/repair.pddl, or the repair.pddl "
                        "beside a tug model file)")
    parser.add_argument("--middleware", choices=("zenoh", "ros2"),
                        help="the robot's middleware, as `dxboard run --middleware`: with ros2 "
                        "a managed node (lifecycle: true) is repaired by reconfigure_node "
                        "(default: $DXBOARD_MIDDLEWARE, else the robot's observers: source: "
                        "kind:; robot directories only)")
    parser.add_argument("--problem", metavar="FILE",
                        help="plan this PDDL problem file as it is (with --domain; no MODEL)")
    parser.add_argument("--write-problem", metavar="FILE",
                        help="also write the PDDL problem of the chosen diagnosis")
    parser.add_argument("--json", action="store_true", help="print JSON")


def run(args: argparse.Namespace) -> int:
    from host.diagnosis.files import load_theory, read_observations
    from host.errors import UserError
    from host.planning.errors import PlanningLimitError
    from host.planning.planners import PLANNERS
    from host.repair.planner import RepairPlanner
    from host.repair.policy import choose

    if args.planner not in PLANNERS:
        raise UserError(f"unknown planner {args.planner!r}",
                        f"use one of {', '.join(sorted(PLANNERS))}")
    if args.problem:
        return _problem_file(args)
    if args.system is None:
        raise UserError("no model given", "dxboard plan MODEL --bad A,B (or --problem FILE "
                        "--domain FILE)")
    planner = RepairPlanner.for_system(args.system, args.domain, managed=_managed(args))
    theory = load_theory(args.system)
    observations = ([o.literal for o in read_observations(args.obs, theory)]
                    if args.obs else [])
    candidates = _candidates(args, planner.model.types, theory.priors)
    try:
        choice = choose(planner, candidates, observations, planner_name=args.planner)
    except PlanningLimitError as exc:
        raise UserError(str(exc), "try --planner fast-downward, or repair fewer at once") from exc
    if args.write_problem:
        problem = planner.problem(choice.bad, observations)
        Path(args.write_problem).write_text(planner.problem_pddl(problem))
    if args.json:
        import json

        print(json.dumps(choice.to_json(), indent=2))
        return 0
    if not choice.plan.steps:
        print("nothing to do: " + choice.reason if choice.strategy == "none" else "empty plan")
        return 0
    print(f"repair {', '.join(sorted(choice.bad))} ({choice.strategy}: {choice.reason})")
    _print_plan(choice.plan)
    return 0


def _print_plan(plan: Plan) -> None:
    for s in plan.steps:
        after = plan.after[s.id]
        wait = f"   after {', '.join(str(i + 1) for i in sorted(after))}" if after else ""
        print(f"{s.id + 1:3d}. {s}{wait}")
    for note in plan.notes:
        print(f"note: {note}")


def _managed(args: argparse.Namespace) -> list[str]:
    """The robot's managed nodes on its middleware, as the daemon finds them."""
    from host.diagnosis.model import SYSTEM_FILE, load_system
    from host.errors import UserError
    from host.observers.section import load_source
    from host.repair.processes import load_processes, managed_nodes

    path = Path(args.system)
    if not (path.is_dir() or path.name == SYSTEM_FILE):
        if args.middleware is not None:
            raise UserError(f"{path}: --middleware is for a robot directory (its processes: "
                            "say which nodes are managed)",
                            "give the robot's directory, or leave --middleware out")
        return []
    middleware = args.middleware or os.environ.get("DXBOARD_MIDDLEWARE") or None
    if middleware not in (None, "zenoh", "ros2"):
        raise UserError(f"DXBOARD_MIDDLEWARE={middleware}: not a middleware",
                        "set it to zenoh or ros2, or unset it")
    model = load_system(path)
    processes = load_processes(path, model)
    if not any(p.lifecycle for p in processes.values()):
        return []  # nothing to decide: the observers need not be read
    # the source alone: the observers themselves are the daemon's (and model check's) to build
    return managed_nodes(processes, middleware or load_source(path, model).kind)


def _problem_file(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.planning.domain import load_domain
    from host.planning.problem_file import plan_problem_file

    if args.domain is None or args.system is not None or args.bad or args.diagnoses \
            or args.obs or args.middleware:
        raise UserError("--problem plans a problem file as it is",
                        "give only --problem FILE --domain FILE (and --planner, --json)")
    plan = plan_problem_file(load_domain(args.domain), Path(args.problem), args.planner)
    if args.json:
        import json

        print(json.dumps(plan.to_json(), indent=2))
    elif plan.steps:
        print(f"plan for {args.problem}:")
        _print_plan(plan)
    else:
        print("nothing to do: the goal holds in the initial state")
    return 0


def _candidates(args: argparse.Namespace, known: Any,
                priors: Mapping[str, float]) -> list[Candidate]:
    from host.errors import UserError
    from host.repair.policy import Candidate, prior_weight

    out: list[Candidate] = []
    if args.diagnoses:
        out += read_diagnoses(args.diagnoses)
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
                f"use names from {args.system}",
            )
    return out


def read_diagnoses(path: str) -> list[Candidate]:
    """The ``diagnoses`` of ``dxboard diagnose --json``."""
    import json

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
