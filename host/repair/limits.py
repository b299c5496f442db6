"""Bounds on repairing: at most N attempts per component in a window, then quarantine.

A repair that does not hold (a device with a permanent fault, a driver that crashes on
start, a device that drops out again and again) must not become a loop of repairs.
``AttemptLimiter`` counts the repair attempts of each component in a sliding window (default 3
in 600 s; times passed in, from the executor's monotonic clock), as a person would count them:

- every execution that touches a component records one attempt (``record``);
- an execution whose effects were all observed marks its attempts *verified* (``verified``);
- the first verified attempt on a component is its bring-up (the robot's power-up, or the
  first repair since the daemon started): it never counts;
- a verified attempt that *held* — no new attempt on that component for ``stable_s`` (60 s)
  after it was verified — no longer counts: the power-up of a robot, or three successful
  repairs of the base on three separate days, never add up to a quarantine;
- a verified attempt followed by a new one within ``stable_s`` *flapped*: the repair did not
  hold (a dropout, a device that hangs again at once), and it counts until the window ends;
- a board reboot (``board_rebooted``: a brown-out, a watchdog reset) is no component's fault:
  the repairs verified before it held, and the bring-up after it is free again.

When a component has used its attempts, the executor *quarantines* it: ``Quarantine`` records
when and why, the executor leaves it in a safe state (switched off or stopped where that is
allowed; never a protected component), and no step touching it runs again until a person
clears it (``Executor.clear_quarantine``).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

DEFAULT_MAX_ATTEMPTS = 3
DEFAULT_WINDOW_S = 600.0
DEFAULT_STABLE_S = 60.0


@dataclass
class _Attempt:
    at: float
    verified_at: float | None = None
    flapped: bool = False


class AttemptLimiter:
    def __init__(self, max_attempts: int = DEFAULT_MAX_ATTEMPTS,
                 window_s: float = DEFAULT_WINDOW_S, stable_s: float = DEFAULT_STABLE_S) -> None:
        if max_attempts < 1 or window_s <= 0 or stable_s < 0:
            raise ValueError("need max_attempts >= 1, window_s > 0 and stable_s >= 0")
        self.max_attempts = max_attempts
        self.window_s = window_s
        self.stable_s = stable_s
        self._attempts: dict[str, deque[_Attempt]] = {}
        self._up: set[str] = set()  # components verified at least once (brought up)

    def _prune(self, component: str, now: float) -> deque[_Attempt]:
        q = self._attempts.setdefault(component, deque())
        kept = deque(a for a in q if a.at > now - self.window_s and not self._held(a, now))
        self._attempts[component] = kept
        return kept

    def _held(self, a: _Attempt, now: float) -> bool:
        return (a.verified_at is not None and not a.flapped
                and now >= a.verified_at + self.stable_s)

    def count(self, component: str, now: float) -> int:
        """Attempts on ``component`` that count at ``now``."""
        return len(self._prune(component, now))

    def exhausted(self, component: str, now: float) -> bool:
        return self.count(component, now) >= self.max_attempts

    def record(self, component: str, now: float) -> int:
        """Count one attempt; the attempts that count, this one included."""
        q = self._prune(component, now)
        for a in q:
            if a.verified_at is not None:
                a.flapped = True  # a new attempt before the last repair held: it did not
        q.append(_Attempt(now))
        return len(q)

    def verified(self, component: str, now: float) -> None:
        """The latest attempt's effects were all observed: it no longer counts once it held
        (at once, if it was the component's bring-up)."""
        q = self._attempts.get(component)
        if not q or q[-1].verified_at is not None:
            return
        if component not in self._up:
            self._up.add(component)
            q.pop()
        else:
            q[-1].verified_at = now

    def reset(self, component: str) -> None:
        self._attempts.pop(component, None)

    def board_rebooted(self) -> None:
        """The board rebooted (a brown-out, a watchdog reset): every device lost power through
        no fault of its own. Verified repairs before it held as far as their components are
        concerned, and each component's next verified attempt is a bring-up again (free);
        attempts that never worked still count."""
        self._up.clear()
        for q in self._attempts.values():
            kept = deque(a for a in q if a.verified_at is None)
            q.clear()
            q.extend(kept)


@dataclass(frozen=True)
class Quarantined:
    """A component taken out of automatic repair: since when, why, and its safe state."""

    component: str
    since: float
    reason: str
    safe_state: str = ""
    by: str = "daemon"  # or "person" (``dxboard quarantine add``)


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
