"""What a diagnosis run returns: ranked minimal diagnoses and whether a bound cut the list.

A ``Diagnosis`` splits the components into ``bad`` (abnormal) and ``good`` (the rest, so
``bad + good = C`` as in paper 000 §IV-C). ``log_prior`` is the log of
``Π_{c∈bad} p_c · Π_{c∈good} (1-p_c)``; ``probability`` is that prior normalised over the
diagnoses of the result (the share of belief each gets if one of them is the truth). A
``DiagnosisResult`` lists the subset-minimal diagnoses most probable first (ties: smaller,
then by names);
``complete`` is False when ``cut_by`` names the bound (``max_card``, ``max_count``,
``time_budget``) that stopped the enumeration. ``explainable`` is False when no assignment of
health states is consistent with the observations (they contradict the model itself); then
``diagnoses`` is empty. The empty diagnosis (``bad = {}``) means everything is consistent with
all components healthy. ``held`` names the observed atoms the diagnoser treated as unknown
this time because they judge a window of time that an upstream change has not yet left
(``lags.py``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any


class Bound(StrEnum):
    MAX_CARD = "max_card"
    MAX_COUNT = "max_count"
    TIME_BUDGET = "time_budget"


@dataclass(frozen=True)
class Diagnosis:
    bad: frozenset[str]
    universe: frozenset[str] = field(default=frozenset(), repr=False, compare=False)
    probability: float = 0.0
    log_prior: float = 0.0

    @property
    def good(self) -> frozenset[str]:
        """The components not in ``bad`` (computed on demand: models can be large)."""
        return self.universe - self.bad

    @property
    def cardinality(self) -> int:
        return len(self.bad)

    def to_json(self, good: bool = False) -> dict[str, Any]:
        """``bad``, ``probability`` and ``cardinality``; the healthy components (``good``,
        the rest of the model) only when asked: on large models they dwarf the rest."""
        out: dict[str, Any] = {
            "bad": sorted(self.bad),
            "probability": self.probability,
            "cardinality": len(self.bad),
        }
        if good:
            out["good"] = sorted(self.good)
        return out


@dataclass(frozen=True)
class DiagnosisResult:
    diagnoses: tuple[Diagnosis, ...]
    complete: bool
    cut_by: Bound | None = None
    explainable: bool = True
    elapsed_s: float = 0.0
    stats: dict[str, int] = field(default_factory=dict)
    held: tuple[str, ...] = ()  # observed atoms treated as unknown this time (lags.py)

    def bad_sets(self) -> list[frozenset[str]]:
        return [d.bad for d in self.diagnoses]

    def to_json(self, good: bool = False) -> dict[str, Any]:
        return {
            "order": "probability",
            "diagnoses": [d.to_json(good) for d in self.diagnoses],
            "complete": self.complete,
            "cut_by": None if self.cut_by is None else self.cut_by.value,
            "explainable": self.explainable,
            "held": list(self.held),
        }


@dataclass
class SearchOutcome:
    """What a search algorithm returns: the bad sets (component indexes), the bound that cut
    the list, and whether any diagnosis exists at all."""

    bad_sets: list[frozenset[int]]
    cut_by: Bound | None = None
    explainable: bool = True


def prior_weights(priors: dict[str, float]) -> tuple[float, dict[str, float]]:
    """``(base, weight)``: ``log_prior(D) = base + sum(weight[c] for c in D)``."""
    base = sum(math.log1p(-p) for p in priors.values())
    return base, {c: math.log(p) - math.log1p(-p) for c, p in priors.items()}


def rank(
    bad_sets: list[frozenset[str]],
    priors: dict[str, float],
    universe: frozenset[str] | None = None,
    weights: tuple[float, dict[str, float]] | None = None,
) -> tuple[Diagnosis, ...]:
    """Diagnoses for ``bad_sets``, most probable first, then smaller, then by names."""
    base, weight = prior_weights(priors) if weights is None else weights
    all_c = frozenset(priors) if universe is None else universe
    scored = []
    for bad in bad_sets:
        lp = base + math.fsum(weight[c] for c in bad)
        scored.append((rank_key(lp, bad), bad, lp))
    scored.sort(key=lambda s: s[0])
    top = max((s[2] for s in scored), default=0.0)
    total = sum(math.exp(s[2] - top) for s in scored)
    return tuple(
        Diagnosis(bad, all_c, math.exp(lp - top) / total, lp)
        for _, bad, lp in scored
    )


def rank_key(log_p: float, bad: Iterable[str]) -> tuple[float, int, list[str]]:
    """The order of diagnoses: most probable first (log-probabilities equal to 9 decimals
    tie), then smaller, then by names. The repair policy ranks the diagnoser's normalised
    probabilities by it too, so the daemon repairs in the order listed."""
    names = sorted(bad)
    return (-round(log_p, 9), len(names), names)
