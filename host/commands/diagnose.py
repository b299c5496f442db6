"""Offline diagnosis: a model and a file of observations in, the minimal diagnoses out.

``dxboard diagnose MODEL --obs FILE [--max-card K] [--max-count N] [--time-budget S]
[--algorithm NAME] [--json]``. MODEL is a robot directory (system.yaml) or a tug model file;
FILE holds one literal a line. The diagnoses come by cardinality, then prior probability; the
output says when a bound cut the list. ``--json`` prints ``{"diagnoses": [{"bad": [...],
"good": [...], "probability": p}, ...], "complete": true|false, "cut_by": ..., "explainable":
...}``.
"""

from __future__ import annotations

import argparse
import json

NAME = "diagnose"
HELP = "diagnose offline: model + observations -> minimal diagnoses"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL", help="robot directory or tug model file")
    parser.add_argument("--obs", required=True, metavar="FILE",
                        help="observations, one literal a line")
    parser.add_argument("--max-card", type=int, default=None, metavar="K",
                        help="largest diagnosis to look for (default: no limit)")
    parser.add_argument("--max-count", type=int, default=1000, metavar="N",
                        help="most diagnoses to list (default: 1000)")
    parser.add_argument("--time-budget", type=float, default=10.0, metavar="S",
                        help="seconds to spend at most (default: 10)")
    parser.add_argument("--algorithm", default="cardinality",
                        help="search algorithm: cardinality or hitting-set")
    parser.add_argument("--json", action="store_true", help="print JSON")


def run(args: argparse.Namespace) -> int:
    from host.diagnosis.diagnoser import Diagnoser
    from host.diagnosis.files import load_theory, read_observations
    from host.diagnosis.search import ALGORITHMS
    from host.errors import UserError

    if args.algorithm not in ALGORITHMS:
        raise UserError(f"unknown algorithm {args.algorithm!r}",
                        f"use one of {', '.join(sorted(ALGORITHMS))}")
    for flag, value in (("--max-card", args.max_card), ("--max-count", args.max_count)):
        if value is not None and value < 0:
            raise UserError(f"{flag} {value} is negative", f"give {flag} 0 or more")
    theory = load_theory(args.model)
    observations = read_observations(args.obs, theory)
    with Diagnoser(theory, algorithm=args.algorithm) as diagnoser:
        for obs in observations:
            diagnoser.observe(obs)
        result = diagnoser.diagnose(max_card=args.max_card, max_count=args.max_count,
                                    time_budget_s=args.time_budget)
    if args.json:
        print(json.dumps(result.to_json(), indent=2))
        return 0
    if not result.explainable:
        print("no diagnosis: the observations contradict the model whatever is broken")
    for i, d in enumerate(result.diagnoses, start=1):
        bad = ", ".join(sorted(d.bad)) or "(nothing: all components healthy)"
        print(f"{i}. p={d.probability:.3f}  bad: {bad}")
    if not result.complete and result.cut_by is not None:
        print(f"(incomplete: the {result.cut_by.value} bound cut the list)")
    return 0
