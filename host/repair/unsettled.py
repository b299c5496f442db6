"""Diagnoses that keep changing: an intermittent fault a person must be told about.

An intermittent fault (a current reading that drops to 0 mA half of every second) turns a
component's diagnosis on and off as fast as the repair debounce, so every pending repair is
superseded and nothing is ever done. The debounce is right not to act on what does not hold;
but the person must hear of it. ``Unsettled`` counts, per component, how often it entered or
left the diagnosis (the union of the minimal diagnoses' bad sets) within ``window_s`` seconds,
and reports a component once its count reaches ``threshold`` — once per window, not at every
change; the changes a running repair makes are not counted. Time is passed in.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field

WINDOW_S = 10.0
THRESHOLD = 6  # three times in and out of the diagnosis within the window


@dataclass(frozen=True)
class Flipping:
    """``component`` entered or left the diagnosis ``changes`` times in ``span_s`` seconds."""

    component: str
    changes: int
    span_s: float

    def text(self) -> str:
        return (f"{self.component}: diagnosis keeps changing ({self.changes} times in "
                f"{self.span_s:.1f} s); no repair starts until it holds for the debounce")


@dataclass
class Unsettled:
    window_s: float = WINDOW_S
    threshold: int = THRESHOLD
    _named: frozenset[str] = frozenset()
    _changes: dict[str, deque[float]] = field(default_factory=dict)
    _told: dict[str, float] = field(default_factory=dict)

    def diagnosed(self, named: Iterable[str], now: float, count: bool = True) -> list[Flipping]:
        """The components named now; returns those to report (sorted by name). With ``count``
        false (a repair is running: its power cycles and restarts change the diagnosis by
        design) the change is taken in but not counted."""
        named = frozenset(named)
        out: list[Flipping] = []
        for c in sorted(named ^ self._named if count else ()):
            q = self._changes.setdefault(c, deque())
            q.append(now)
            while q and q[0] < now - self.window_s:
                q.popleft()
            if len(q) >= self.threshold and now - self._told.get(c, -self.window_s) \
                    >= self.window_s:
                self._told[c] = now
                out.append(Flipping(c, len(q), now - q[0]))
        self._named = named
        return out
