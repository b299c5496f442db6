"""What a plan-execution diagnosis returns: alternative histories, ranked and classified.

An ``AlternativeHistory`` is one minimal diagnosis: the faults that replace the executed
history's steps (fault modes) or join it (exogenous events), each with its class:

- ``component fault``: a fault mode caused by a component layer 0 diagnosed broken;
- ``action fault``: a fault mode otherwise (the action went wrong by itself);
- ``exogenous event``: something happened between two steps that nobody commanded;
- ``plan error``: no alternative history explains what was seen, although the plan ran as
  intended up to the failing step (``planerror.py`` says which condition the domain lacks).

``rank`` orders the histories by cardinality then probability (or the other way round) and
gives each its probability: the product of its faults' priors, normalised over the histories
listed. ``correct_kb`` is the knowledge base the most probable history implies at the end,
as changes to the dispatcher's (``certain`` are the changes every listed history implies).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from host.plandiag.limits import Order
from host.plandiag.model import FaultKind
from host.plandiag.problem import Fault, HistoryProblem, simulate


class FaultClass(StrEnum):
    COMPONENT = "component fault"
    ACTION = "action fault"
    EVENT = "exogenous event"
    PLAN_ERROR = "plan error"


@dataclass(frozen=True)
class ClassifiedFault:
    fault: Fault
    cls: FaultClass
    broken: tuple[str, ...] = ()  # the components layer 0 found broken (component faults)

    def describe(self) -> str:
        why = f" (layer 0: {', '.join(self.broken)} broken)" if self.broken else ""
        return f"{self.cls.value}: {self.fault.label()}{why}"

    def to_json(self) -> dict[str, Any]:
        f = self.fault
        out: dict[str, Any] = {"class": self.cls.value, "kind": f.kind.value,
                               "action": f.op.name, "args": list(f.op.args),
                               "prior": f.prior, "label": f.label()}
        if f.kind is FaultKind.MODE:
            out["step"] = f.at
            out["mode_of"] = f.mode_of
        else:
            out["before_step"] = f.at
        if self.broken:
            out["broken_components"] = list(self.broken)
        return out


@dataclass(frozen=True)
class AlternativeHistory:
    faults: tuple[ClassifiedFault, ...]
    probability: float
    log_prior: float

    @property
    def ids(self) -> frozenset[int]:
        return frozenset(c.fault.id for c in self.faults)

    @property
    def cardinality(self) -> int:
        return len(self.faults)

    def classes(self) -> list[FaultClass]:
        return sorted({c.cls for c in self.faults})

    def summary(self) -> str:
        return "; ".join(c.describe() for c in self.faults) or "nothing went wrong"

    def to_json(self) -> dict[str, Any]:
        return {"probability": self.probability, "cardinality": self.cardinality,
                "faults": [c.to_json() for c in self.faults]}


def classify(fault: Fault, confirmed: Mapping[str, tuple[str, ...]]) -> ClassifiedFault:
    if fault.kind is FaultKind.EVENT:
        return ClassifiedFault(fault, FaultClass.EVENT)
    broken = confirmed.get(fault.op.name, ())
    return ClassifiedFault(fault, FaultClass.COMPONENT if broken else FaultClass.ACTION, broken)


def rank(problem: HistoryProblem, diagnoses: Iterable[frozenset[int]], order: Order,
         confirmed: Mapping[str, tuple[str, ...]]) -> list[AlternativeHistory]:
    scored = []
    for d in diagnoses:
        faults = sorted((problem.faults[f] for f in d), key=lambda f: (f.at, f.kind, f.id))
        lp = sum(math.log(f.prior) for f in faults)
        where = [(f.at, f.kind.value, f.action()) for f in faults]
        key = (len(faults), -lp, where) if order is Order.CARDINALITY else (-lp, len(faults),
                                                                            where)
        scored.append((key, faults, lp))
    scored.sort(key=lambda s: s[0])
    top = max((s[2] for s in scored), default=0.0)
    total = sum(math.exp(s[2] - top) for s in scored)
    return [AlternativeHistory(tuple(classify(f, confirmed) for f in faults),
                               math.exp(lp - top) / total, lp)
            for _, faults, lp in scored]


@dataclass(frozen=True)
class KbCorrection:
    """The knowledge base at the end, as the most probable history implies."""

    kb: tuple[str, ...]  # every atom true at the end
    observed: tuple[str, ...]  # changes the last observations made already (as literals)
    set_true: tuple[str, ...]  # inferred: atoms the dispatcher believes false
    set_false: tuple[str, ...]  # inferred: atoms the dispatcher believes true
    certain: tuple[str, ...]  # the inferred changes (as literals) every listed history implies

    def changes(self) -> list[str]:
        return list(self.set_true) + [f"~{a}" for a in self.set_false]

    def to_json(self) -> dict[str, Any]:
        return {"kb": list(self.kb), "observed": list(self.observed),
                "set_true": list(self.set_true), "set_false": list(self.set_false),
                "certain": list(self.certain)}


def _literals(problem: HistoryProblem, state: int, mask: int) -> tuple[str, ...]:
    return tuple(("" if (state >> a) & 1 else "~") + problem.atom_name(a)
                 for a in range(len(problem.task.atoms)) if (mask >> a) & 1)


def correct_kb(problem: HistoryProblem, before: int, after: int,
               histories: list[AlternativeHistory]) -> KbCorrection | None:
    """The KB the best history implies at the last point, against the dispatcher's KB there
    ``before`` and ``after`` the last observations overrode it."""
    finals = [run.states[-1] for run in (simulate(problem, h.ids) for h in histories)
              if run.consistent]
    if not finals:
        return None
    best = finals[0]
    n = len(problem.task.atoms)
    diff = best ^ after
    agree = ~0
    for s in finals:
        agree &= ~(s ^ best)
    return KbCorrection(
        kb=tuple(sorted(problem.atom_name(a) for a in range(n) if (best >> a) & 1)),
        observed=_literals(problem, after, before ^ after),
        set_true=tuple(problem.atom_name(a) for a in range(n) if ((diff & best) >> a) & 1),
        set_false=tuple(problem.atom_name(a) for a in range(n)
                        if (diff >> a) & 1 and not (best >> a) & 1),
        certain=_literals(problem, best, diff & agree),
    )
