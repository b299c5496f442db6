"""Explain a failed mission step offline: an executed history + the mission domain -> why.

``dxboard explain HISTORY.json DOMAIN_DIR [--engine sat|tree|naive] [--order cardinality|
probability] [--max-card K] [--max-count N] [--time-budget S] [--no-region] [--json]``.

DOMAIN_DIR holds ``mission.pddl`` (the mission domain: typed STRIPS with negative
preconditions and equality) and ``faults.pddl`` (how execution goes wrong: a PDDL domain over
the same types and predicates, which it may leave out). Each action of ``faults.pddl`` is
preceded by one annotation comment:

  ; @mode ACTION prior=P [components=C1,C2]   a fault mode: ACTION ran, but like this; its
                                              first parameters are ACTION's, more may follow
  ; @event prior=P                            an exogenous event: may happen between steps

A mode's P is the probability that ACTION goes wrong that way when it runs; a mode with extra
parameters shares P evenly among their groundings (navigate-elsewhere to one of 4 places:
P/4 each). An event's P is its probability per grounding and gap.

The bounds mean the same in every engine: --max-card K lists the minimal histories of at most K
faults; --max-count N keeps N of them, the N smallest (--order cardinality) or the N most
probable (--order probability); "complete" is false exactly when a bound left one out (or the
time budget ran out), and "explainable" is false only when no alternative history exists.

HISTORY.json is the mission journal's record: ``objects`` (name: type), ``init`` (the
knowledge base before the first step, atoms like ``at(tedusar,start)``), ``steps`` (each with
``action``, ``args``, ``start``, ``end``, ``result`` success | fail | halted | not-run, and
``observations``: ``{"atom": ..., "value": true|false, "where": pre|during|post}``), the
``alarm`` (``step`` from 1, ``where``, ``critical``, ``atoms``, ``message``) and
``components`` (layer 0: ``healthy`` and ``broken`` component names).

It prints the alarm, the symptoms (local: during a step or at its expected-state check;
propagated: at a precondition check), the fault region, the minimal alternative histories
(fault modes in place of steps, events between them) ranked, the most probable one as its path
through the context tree, the class of the fault (component fault, action fault, exogenous
event, plan error with the condition the domain lacks) and the corrected knowledge base.
``--json`` prints the same as one object.
"""

from __future__ import annotations

import argparse
import json

NAME = "explain"
HELP = "explain a failed mission step: history + mission domain -> alternative histories"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("history", metavar="HISTORY.json", help="the executed history")
    parser.add_argument("domain", metavar="DOMAIN_DIR",
                        help="directory with mission.pddl and faults.pddl (or mission.pddl)")
    parser.add_argument("--faults", metavar="FILE",
                        help="fault modes and events (default: DOMAIN_DIR/faults.pddl)")
    parser.add_argument("--engine", default="sat",
                        help="inference engine: sat (default), tree (the context tree) or naive")
    parser.add_argument("--order", default="cardinality",
                        help="list histories by cardinality (default) or probability")
    parser.add_argument("--max-card", type=int, default=3, metavar="K",
                        help="most faults in one alternative history (default: 3)")
    parser.add_argument("--max-count", type=int, default=100, metavar="N",
                        help="most alternative histories to list (default: 100)")
    parser.add_argument("--time-budget", type=float, default=10.0, metavar="S",
                        help="seconds to spend at most (default: 10)")
    parser.add_argument("--no-region", action="store_true",
                        help="search the whole history, not the fault region first")
    parser.add_argument("--json", action="store_true", help="print JSON")


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.plandiag.engines import ENGINES
    from host.plandiag.history import load_history
    from host.plandiag.limits import Limits, Order
    from host.plandiag.model import load_model
    from host.plandiag.pipeline import explain_history
    from host.plandiag.text import render

    if args.engine not in ENGINES:
        raise UserError(f"unknown engine {args.engine!r}", f"use one of {', '.join(ENGINES)}")
    if args.order not in {o.value for o in Order}:
        raise UserError(f"unknown order {args.order!r}", "use cardinality or probability")
    for flag, value in (("--max-card", args.max_card), ("--max-count", args.max_count)):
        if value < 0:
            raise UserError(f"{flag} {value} is negative", f"give {flag} 0 or more")
    if args.time_budget <= 0:
        raise UserError(f"--time-budget {args.time_budget} is not positive",
                        "give the seconds to spend, e.g. --time-budget 10")
    model = load_model(args.domain, args.faults)
    history = load_history(args.history)
    limits = Limits(args.max_card, args.max_count, args.time_budget, Order(args.order))
    explanation = explain_history(model, history, args.engine, limits,
                                  use_region=not args.no_region)
    if args.json:
        print(json.dumps(explanation.to_json(), indent=2))
    else:
        print("\n".join(render(explanation)))
    return 0
