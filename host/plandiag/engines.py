"""The inference engines behind one name -> callable registry, and naive enumeration.

Every engine takes the ``HistoryProblem``, the universe of faults it may use (the fault
region's suspects, or None for all) and the ``Limits``, and returns an ``ExplainOutcome`` with
the same minimal diagnoses (``tests/plandiag`` cross-checks them on random histories):

- ``tree``: the context tree of paper 004 (``tree.py``), the explainable reference;
- ``sat``: the SAT encoding (``sat.py``), for long histories;
- ``naive``: every fault set by size, each simulated from the start (``problem.simulate``),
  supersets of diagnoses skipped; the benchmark's baseline and a third opinion in the tests.
  Whether its ``max_card`` cut anything it asks the SAT encoding (``sat.any_beyond``, one
  solver call): enumerating every larger set would never end.

All three mean the same by the bounds (``limits.py``): under ``order=probability`` a
``max_count`` keeps the most probable diagnoses (``most_probable`` makes the tree and naive
list all up to ``max_card`` and keep the best; RC2 finds them in that order), and a cut is
reported only when it left a diagnosis out.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import replace

from host.diagnosis.result import Bound
from host.plandiag.limits import Deadline, ExplainOutcome, Limits, Order
from host.plandiag.problem import HistoryProblem, simulate
from host.plandiag.sat import any_beyond, sat_engine
from host.plandiag.tree import context_tree

Engine = Callable[[HistoryProblem, frozenset[int] | None, Limits], ExplainOutcome]


def naive(problem: HistoryProblem, universe: frozenset[int] | None,
          limits: Limits) -> ExplainOutcome:
    out = ExplainOutcome()
    if problem.impossible_step(universe) is not None:
        return out  # complete and empty: proven unexplainable
    ids = [f.id for f in problem.faults if universe is None or f.id in universe]
    limit = len(ids) if limits.max_card is None else min(limits.max_card, len(ids))
    deadline = Deadline(limits.time_budget_s)
    for k in range(limit + 1):
        for combo in itertools.combinations(ids, k):
            s = frozenset(combo)
            if any(d <= s for d in out.diagnoses):
                continue
            if deadline.passed():
                out.cut_by = Bound.TIME_BUDGET
                return out
            out.nodes += 1
            if simulate(problem, s).consistent:
                if limits.max_count is not None and len(out.diagnoses) >= limits.max_count:
                    out.cut_by = Bound.MAX_COUNT
                    return out
                out.diagnoses.append(s)
    if limit < len(ids) and frozenset() not in out.diagnoses:
        more = any_beyond(problem, universe, out.diagnoses, deadline.left())
        if more is None or more:
            out.cut_by = Bound.TIME_BUDGET if more is None else Bound.MAX_CARD
    return out


def most_probable(engine: Engine) -> Engine:
    """``engine`` made to keep the ``max_count`` *most probable* diagnoses under
    ``order=probability`` (it lists them by size): it lists every one up to ``max_card`` and
    keeps the best. The SAT engine needs no wrapper: RC2 finds them in that order."""

    def run(problem: HistoryProblem, universe: frozenset[int] | None,
            limits: Limits) -> ExplainOutcome:
        n = limits.max_count
        if limits.order is not Order.PROBABILITY or n is None:
            return engine(problem, universe, limits)
        out = engine(problem, universe, replace(limits, max_count=None))
        if len(out.diagnoses) > n:
            out.diagnoses.sort(key=lambda d: (cost(problem, d), len(d), sorted(d)))
            del out.diagnoses[n:]
            out.cut_by = out.cut_by or Bound.MAX_COUNT
        return out

    return run


def cost(problem: HistoryProblem, diagnosis: frozenset[int]) -> float:
    """``-log`` of the diagnosis's prior (the product of its faults' priors): lower is more
    probable. ``result.rank`` orders the histories by it too."""
    return math.fsum(-math.log(problem.faults[f].prior) for f in diagnosis)


ENGINES: dict[str, Engine] = {"sat": sat_engine, "tree": most_probable(context_tree),
                              "naive": most_probable(naive)}
DEFAULT_ENGINE = "sat"
