"""Several diagnoses: which one to repair, and a record of why.

The paper's repair engine always planned for the first diagnosis. Ours plans for each
candidate (planning takes milliseconds) and decides:

1. no candidate, or the most probable one empty -> nothing to repair;
2. one candidate -> repair it;
3. several -> if repairing *all* of them at once (the union of their bad sets) costs at most
   ``union_slack`` more than repairing the most probable one alone, repair them all: no need
   to tell them apart, and the fault is gone whichever diagnosis is true;
4. otherwise repair the most probable one (the executor verifies, re-diagnoses and replans
   if the fault persists); a candidate that cannot be repaired at all is skipped, and said so.

Acting first to tell diagnoses apart (a sensing action) needs observation actions in the
domain and is not done yet. Probabilities come from the diagnoser (``Diagnosis.probability``)
or, for hand-given candidates, from the components' priors (``prior_weight``); candidates are
ranked as the diagnoser lists them (``host.diagnosis.result.rank_key``: most probable, then
smaller, then by names), so the daemon repairs the diagnoser's first.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from host.diagnosis.result import rank_key
from host.planning.errors import NoPlanError
from host.planning.plan import Plan

if TYPE_CHECKING:
    from host.diagnosis.logic import Literal
    from host.repair.planner import RepairPlanner

DEFAULT_UNION_SLACK = 1.0
DEFAULT_PRIOR = 0.01


@dataclass(frozen=True)
class Candidate:
    """One diagnosis to choose from."""

    bad: frozenset[str]
    probability: float


@dataclass(frozen=True)
class Choice:
    """What the policy decided: the bad set repaired, its plan, the strategy and why."""

    bad: frozenset[str]
    plan: Plan
    strategy: str  # "none", "single", "all-at-once", "most-probable"
    reason: str

    def to_json(self) -> dict[str, Any]:
        return {
            **self.plan.to_json(),
            "repairs": sorted(self.bad),
            "strategy": self.strategy,
            "reason": self.reason,
        }


def prior_weight(bad: Iterable[str], priors: Mapping[str, float]) -> float:
    """``Π p_c / (1 - p_c)`` over the bad components: proportional to the diagnosis' prior."""
    w = 0.0
    for c in bad:
        p = min(max(priors.get(c, DEFAULT_PRIOR), 1e-9), 1 - 1e-9)
        w += math.log(p / (1 - p))
    return math.exp(w)


def normalise(cands: Sequence[Candidate]) -> list[Candidate]:
    total = sum(c.probability for c in cands)
    if total <= 0:
        return [Candidate(c.bad, 1 / len(cands)) for c in cands]
    return [Candidate(c.bad, c.probability / total) for c in cands]


def _fmt(bad: frozenset[str]) -> str:
    return "{" + ", ".join(sorted(bad)) + "}"


def choose(
    planner: RepairPlanner,
    candidates: Sequence[Candidate],
    observations: Sequence[Literal] = (),
    union_slack: float = DEFAULT_UNION_SLACK,
    planner_name: str = "astar",
) -> Choice:
    """Decide which diagnosis to repair (see the module docstring)."""
    ranked = sorted(
        normalise(candidates) if candidates else [],
        key=lambda c: rank_key(math.log(c.probability) if c.probability > 0 else -math.inf,
                               c.bad),
    )
    if not ranked or not ranked[0].bad:
        empty = planner.plan((), observations, planner_name)
        return Choice(frozenset(), empty, "none", "no component is diagnosed abnormal")
    plans: list[tuple[Candidate, Plan]] = []
    skipped: list[str] = []
    for c in ranked:
        try:
            plans.append((c, planner.plan(c.bad, observations, planner_name)))
        except NoPlanError as exc:
            if len(ranked) == 1:
                raise
            skipped.append(f"{_fmt(c.bad)} cannot be repaired ({exc.message})")
    if not plans:
        raise NoPlanError(
            "none of the diagnoses can be repaired: " + "; ".join(skipped),
            "repair by hand; the plan would need actions the domain does not have",
        )
    skip_note = ("; skipped " + "; ".join(skipped)) if skipped else ""
    best, best_plan = plans[0]
    if len(ranked) == 1:
        return Choice(best.bad, best_plan, "single", "the only diagnosis" + skip_note)
    union = frozenset().union(*(c.bad for c, _ in plans))
    if len(plans) > 1:
        try:
            union_plan: Plan | None = planner.plan(union, observations, planner_name)
        except NoPlanError:
            union_plan = None
        if union_plan is not None and union_plan.cost <= best_plan.cost + union_slack:
            return Choice(
                union,
                union_plan,
                "all-at-once",
                f"repairing all {len(plans)} diagnoses at once costs {union_plan.cost:g} vs "
                f"{best_plan.cost:g} for the most probable {_fmt(best.bad)} alone "
                f"(within {union_slack:g}): no need to tell them apart" + skip_note,
            )
        extra = (
            f"repairing all at once would cost {union_plan.cost:g}"
            if union_plan is not None
            else "their union cannot be repaired"
        )
    else:
        extra = "the other diagnoses cannot be repaired"
    return Choice(
        best.bad,
        best_plan,
        "most-probable",
        f"the most probable diagnosis {_fmt(best.bad)} (p={best.probability:.2f}) costs "
        f"{best_plan.cost:g}; {extra}; the executor verifies and replans if the fault "
        "persists" + skip_note,
    )
