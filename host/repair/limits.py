"""Bounds on repairing: at most N attempts per component in a window, then quarantine.

A repair that does not hold (a device with a permanent fault, a driver that crashes on
start) must not become a loop of repairs. ``AttemptLimiter`` counts the repair attempts of
each component in a sliding window (default 3 in 600 s; times passed in, from the executor's
monotonic clock). When a component has used its attempts, the executor *quarantines* it:
``Quarantine`` records when and why, the executor leaves it in a safe state (switched off or
stopped where that is allowed; never a protected component), and no step touching it runs
again until a person calls ``clear(component)`` (``Executor.clear_quarantine``).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

DEFAULT_MAX_ATTEMPTS = 3
DEFAULT_WINDOW_S = 600.0


class AttemptLimiter:
    def __init__(self, max_attempts: int = DEFAULT_MAX_ATTEMPTS,
                 window_s: float = DEFAULT_WINDOW_S) -> None:
        if max_attempts < 1 or window_s <= 0:
            raise ValueError("need max_attempts >= 1 and window_s > 0")
        self.max_attempts = max_attempts
        self.window_s = window_s
        self._times: dict[str, deque[float]] = {}

    def _prune(self, component: str, now: float) -> deque[float]:
        q = self._times.setdefault(component, deque())
        while q and q[0] <= now - self.window_s:
            q.popleft()
        return q

    def count(self, component: str, now: float) -> int:
        """Attempts on ``component`` in the window ending at ``now``."""
        return len(self._prune(component, now))

    def exhausted(self, component: str, now: float) -> bool:
        return self.count(component, now) >= self.max_attempts

    def record(self, component: str, now: float) -> int:
        """Count one attempt; the attempts in the window, this one included."""
        q = self._prune(component, now)
        q.append(now)
        return len(q)

    def reset(self, component: str) -> None:
        self._times.pop(component, None)


@dataclass(frozen=True)
class Quarantined:
    """A component taken out of automatic repair: since when, why, and its safe state."""

    component: str
    since: float
    reason: str
    safe_state: str = ""


class Quarantine:
    def __init__(self) -> None:
        self._entries: dict[str, Quarantined] = {}

    def add(self, entry: Quarantined) -> None:
        self._entries.setdefault(entry.component, entry)

    def clear(self, component: str) -> bool:
        """A person released ``component``; True if it was quarantined."""
        return self._entries.pop(component, None) is not None

    def __contains__(self, component: object) -> bool:
        return component in self._entries

    def get(self, component: str) -> Quarantined | None:
        return self._entries.get(component)

    @property
    def components(self) -> frozenset[str]:
        return frozenset(self._entries)

    def entries(self) -> list[Quarantined]:
        return list(self._entries.values())
