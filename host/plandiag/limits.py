"""What every inference engine takes and returns: the bounds of a search and its outcome.

``Limits`` bounds a search as layer 0's diagnoser does: ``max_card`` (the most faults in one
alternative history), ``max_count`` (the most diagnoses to list), ``time_budget_s`` (seconds,
measured with ``time.perf_counter``, the only clock this package reads and only to bound
computation) and ``order`` (``cardinality``: fewest faults first; ``probability``: most
probable first, which matters when a bound cuts the list). ``ExplainOutcome`` holds the minimal
diagnoses found (sets of fault ids) and the bound that cut the list (``host.diagnosis.result.
Bound``), set only when a diagnosis was really left out (or time ran out), so ``complete``
means the list is every minimal diagnosis. ``explainable`` follows from the two, the same for
every engine: False exactly when the search was complete and found nothing (it proved that no
alternative history explains the observations).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from enum import StrEnum

from host.diagnosis.result import Bound


class Order(StrEnum):
    CARDINALITY = "cardinality"
    PROBABILITY = "probability"


@dataclass(frozen=True)
class Limits:
    max_card: int | None = 3
    max_count: int | None = 100
    time_budget_s: float | None = 10.0
    order: Order = Order.CARDINALITY


@dataclass
class ExplainOutcome:
    diagnoses: list[frozenset[int]] = field(default_factory=list)
    cut_by: Bound | None = None
    nodes: int = 0  # context-tree nodes expanded, histories simulated, or solver calls
    elapsed_s: float = 0.0

    @property
    def complete(self) -> bool:
        return self.cut_by is None

    @property
    def explainable(self) -> bool:
        """False only when the engine proved that no diagnosis exists at all."""
        return bool(self.diagnoses) or self.cut_by is not None


class Deadline:
    """A wall-clock budget, checked between units of work."""

    def __init__(self, seconds: float | None) -> None:
        self.at = math.inf if seconds is None else time.perf_counter() + seconds

    def passed(self) -> bool:
        return time.perf_counter() >= self.at

    def left(self) -> float | None:
        """The seconds left (None: no budget), at least a millisecond."""
        return None if self.at == math.inf else max(self.at - time.perf_counter(), 1e-3)
