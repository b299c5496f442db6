"""Offline diagnosis: a model and a file of observations in, the minimal diagnoses out.

``dxboard diagnose MODEL --obs FILE [--max-card K] [--max-count N] [--time-budget S]
[--min-card-only] [--algorithm NAME] [--json] [--good]``. MODEL is a robot directory
(system.yaml) or a tug model file; FILE holds one observation a line (``ok(/scan)``,
``~on(jaguar)``, ``unknown ok(/map)``, ``LITERAL @ SECONDS``; see host/diagnosis/files.py).

The subset-minimal diagnoses come **most probable first**: by the prior probability of the
diagnosis, ``Π p(c) over the bad components · Π (1 - p(c)) over the good ones``, with the
components' priors from the model (0.01 where it gives none), then by size and names; ``p=``
is that probability normalised over the listed diagnoses. ``--max-count N`` keeps the N most
probable. ``--min-card-only`` asks for the minimal-cardinality diagnoses only (the smallest
size that has any), the fast request on large circuits. The output says when a bound cut the
list. The exit code is 0 when there are diagnoses, 1 when there is none (the observations
contradict the model whatever is broken, or a bound cut the search before the first), and 2
on bad input. ``--json`` prints ``{"order": "probability", "diagnoses": [{"bad": [...],
"probability": p, "cardinality": k}, ...], "complete": true|false, "cut_by": ...,
"explainable": ...}``; ``--good`` adds each diagnosis' healthy components (``"good"``).
A model file's parsed form, compiled for the SAT engine (its clauses as numbers, its circuit
structure), is kept in ``$XDG_CACHE_HOME/dxboard/models`` (default ``~/.cache/dxboard/models``)
and read back while the file is unchanged; deleting it is safe.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from host.diagnosis.encoding import Encoding

NAME = "diagnose"
HELP = "diagnose offline: model + observations -> minimal diagnoses, most probable first"

#: the algorithms of host/diagnosis/search.py's registry (a test keeps the two equal; named
#: here so that ``--help`` does not load the SAT engine)
ALGORITHMS = {
    "auto": "cardinality, or top-level for minimal-cardinality requests on large circuits "
            "(the fastest measured)",
    "cardinality": "incremental SAT, by size",
    "top-level": "MaxSAT over the undominated components of a circuit, then cardinality",
    "maxsat": "core-guided MaxSAT (RC2)",
    "hitting-set": "conflicts from unsatisfiable cores, implicit hitting sets",
}
DEFAULT_ALGORITHM = "auto"


def _count(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not a positive count")
    return value


def _card(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{value} is negative; give 0 or more")
    return value


def _seconds(text: str) -> float:
    value = float(text)
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text} is not a positive number of seconds")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL", help="robot directory or tug model file")
    parser.add_argument("--obs", required=True, metavar="FILE",
                        help="observations, one literal a line")
    parser.add_argument("--max-card", type=_card, default=None, metavar="K",
                        help="largest diagnosis to look for (default: no limit)")
    parser.add_argument("--max-count", type=_count, default=1000, metavar="N",
                        help="keep the N most probable diagnoses (default: 1000)")
    parser.add_argument("--time-budget", type=_seconds, default=10.0, metavar="S",
                        help="seconds to spend at most (default: 10)")
    parser.add_argument("--min-card-only", action="store_true",
                        help="only the minimal-cardinality diagnoses (the smallest size)")
    parser.add_argument("--algorithm", default=DEFAULT_ALGORITHM, choices=sorted(ALGORITHMS),
                        metavar="NAME",
                        help=f"search algorithm (default: {DEFAULT_ALGORITHM}): "
                        + "; ".join(f"{k}: {v}" for k, v in ALGORITHMS.items()))
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument("--good", action="store_true",
                        help="with --json: list each diagnosis' healthy components too")


def run(args: argparse.Namespace) -> int:
    from host.diagnosis.files import load_encoded

    # the model lives as long as the command: out of the collector's sight meanwhile, its
    # ~60,000 objects are not walked again by every collection the search triggers (c7552:
    # about 10 ms less CPU a run, benchmarks/RESULTS.md), nor by the one their own unpickling
    # would set off (frozen before the collector runs again: 4-12 ms more on c7552); given
    # back at the end, so a caller in the same process (the tests) finds it as it was
    collecting = gc.isenabled()
    gc.disable()
    try:
        encoding = load_encoded(args.model)
        gc.freeze()
    finally:
        if collecting:
            gc.enable()
    try:
        return _diagnose(args, encoding)
    finally:
        gc.unfreeze()


def _diagnose(args: argparse.Namespace, encoding: Encoding) -> int:
    from host.commands.model import print_notes
    from host.diagnosis.diagnoser import Diagnoser
    from host.diagnosis.files import read_observations

    theory = encoding.theory
    print_notes(theory)
    observations = read_observations(args.obs, theory)
    with Diagnoser(theory, algorithm=args.algorithm, encoding=encoding) as diagnoser:
        for obs in observations:
            diagnoser.observe(obs)
        result = diagnoser.diagnose(max_card=args.max_card, max_count=args.max_count,
                                    time_budget_s=args.time_budget,
                                    min_card_only=args.min_card_only)
    code = 0 if result.diagnoses else 1
    if args.json:
        json.dump(result.to_json(good=args.good), sys.stdout, indent=1)
        sys.stdout.write("\n")
        return code
    if not result.explainable:
        print("no consistent diagnosis: the observations contradict the model whatever is "
              "broken (check the observations, or the model)")
        return code
    if result.diagnoses:
        print("diagnoses, most probable first (p: probability among those listed):")
    else:
        print("no diagnosis found within the bounds")
    for i, d in enumerate(result.diagnoses, start=1):
        bad = ", ".join(sorted(d.bad)) or "(nothing: all components healthy)"
        print(f"{i}. p={d.probability:.3f}  bad: {bad}")
    if not result.complete and result.cut_by is not None:
        print(f"(incomplete: the {result.cut_by.value} bound cut the list)")
    return code
