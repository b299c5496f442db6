"""The inference engines behind one name -> callable registry, and naive enumeration.

Every engine takes the ``Problem``, the universe of faults it may use (the fault region's
suspects, or None for all) and the ``Limits``, and returns an ``Outcome`` with the same minimal
diagnoses (``tests/plandiag`` cross-checks them on random histories):

- ``tree``: the context tree of paper 004 (``tree.py``), the explainable reference;
- ``sat``: the SAT encoding (``sat.py``), for long histories;
- ``naive``: every fault set by size, each simulated from the start (``problem.simulate``),
  supersets of diagnoses skipped; the benchmark's baseline and a third opinion in the tests.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

from host.diagnosis.result import Bound
from host.plandiag.limits import Deadline, Limits, Outcome
from host.plandiag.problem import Problem, simulate
from host.plandiag.sat import sat_engine
from host.plandiag.tree import context_tree

Engine = Callable[[Problem, frozenset[int] | None, Limits], Outcome]


def naive(problem: Problem, universe: frozenset[int] | None, limits: Limits) -> Outcome:
    out = Outcome()
    if problem.impossible_step(universe) is not None:
        out.explainable = False
        return out
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
    if limit == len(ids):
        out.explainable = bool(out.diagnoses)
    return out


ENGINES: dict[str, Engine] = {"sat": sat_engine, "tree": context_tree, "naive": naive}
DEFAULT_ENGINE = "sat"
