"""When a search may stop: ``max_count`` diagnoses, and they are the most probable ones.

Diagnoses are ranked by their prior ``Π_{c∈D} p_c · Π_{c∉D} (1-p_c)``; in logs,
``base + Σ_{c∈D} w_c`` with ``w_c = log(p_c / (1-p_c))`` (``result.prior_weights``). Every
search algorithm finds diagnoses in order of non-decreasing size, not of probability, so
"stop after N" would keep the N *smallest*. A ``Quota`` makes the cut exact instead: it keeps
the N best log priors found so far, and says the search may stop at size ``k`` only when the
N-th best is at least ``UB(k)``, the best log prior any diagnosis of size ``k`` or more can
have (``base`` plus the largest sum of ``j >= k`` weights, taken from the largest weights
down). Nothing found later can then displace one of the N.

With equal priors below 0.5 (circuits, and robot models without priors) ``UB(k)`` is the
prior of size ``k`` itself, so the search stops at the N-th diagnosis, as a plain count
would. With unequal priors it may have to finish the size it is at, or go on to larger sizes
(priors of 0.5 and above make larger diagnoses no less likely). The caller ranks what was
found and keeps the first N.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence

EPS = 1e-9  # log-prior tolerance: equal priors computed in another order are a tie


def upper_bounds(weights: Sequence[float]) -> list[float]:
    """``ub[k]``: the best score (sum of weights) a diagnosis of size ``k`` or more can have
    (computed once per model: it does not depend on the observations)."""
    sums = [0.0]
    for w in sorted(weights, reverse=True):
        sums.append(sums[-1] + w)
    ub = sums[:]
    for k in range(len(sums) - 2, -1, -1):
        ub[k] = max(sums[k], ub[k + 1])
    return ub


class Quota:
    """``count`` wanted diagnoses (None: all) under per-component log-odds ``weights``."""

    def __init__(self, count: int | None, weights: Sequence[float],
                 ub: Sequence[float] | None = None) -> None:
        self.count = count
        self.weights = weights
        self._ub = upper_bounds(weights) if ub is None else ub
        self._heap: list[float] = []  # the `count` best scores, smallest first

    def reset(self) -> None:
        self._heap = []

    def add(self, bad: frozenset[int]) -> None:
        """Record a found diagnosis (component indexes)."""
        if self.count is None:
            return
        score = math.fsum(self.weights[i] for i in bad)
        if len(self._heap) < self.count:
            heapq.heappush(self._heap, score)
        elif score > self._heap[0]:
            heapq.heapreplace(self._heap, score)

    def reached(self, k: int) -> bool:
        """True when no diagnosis of size ``k`` or more can enter the ``count`` best."""
        if self.count is None or len(self._heap) < self.count:
            return False
        if k >= len(self._ub):
            return True
        return self._heap[0] >= self._ub[k] - EPS
