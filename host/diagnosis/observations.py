"""Observations: literals with a time, a source and a validity, kept as the set S ⊕ o.

Paper 000 §IV-C integrates each observation ``o`` into the set ``S`` as ``S ⊕ o``: a new
literal ``L`` replaces ``¬L`` (and an older ``L``). On top of that each ``Observation`` has a
``validity`` in seconds: an observer repeats its observation while it holds, and one that falls
silent for longer than the validity lets its literal *expire* — the atom becomes unknown (it is
dropped, not negated: unknown is not false). ``validity=None`` means valid until replaced.
Time is passed in (``now``, seconds on any monotonic clock the caller chooses); this module
never reads a clock. The daemon keeps exactly one ``ObservationSet``: the diagnoser diagnoses
snapshots of it (``literals()``), the repair executor waits on it (``host.repair.beliefs``
listens through ``listen``: every add, refresh, retraction and expiry calls the listeners).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from host.diagnosis.logic import Literal, parse_literal


# a literal in the diagnoser's observation set; host/events.py's Observation is the change of
# one on the daemon's event stream, a layer above (scripts/names.py)
@dataclass(frozen=True)
class Observation:
    literal: Literal
    time: float = 0.0
    source: str = ""
    validity: float | None = None

    @property
    def expires_at(self) -> float | None:
        return None if self.validity is None else self.time + self.validity

    @staticmethod
    def parse(text: str, time: float = 0.0, source: str = "",
              validity: float | None = None) -> Observation:
        return Observation(parse_literal(text), time, source, validity)


class ObservationSet:
    """The current observations, one per atom (``S ⊕ o``), with expiry."""

    def __init__(self) -> None:
        self._by_atom: dict[str, Observation] = {}
        self._listeners: list[Callable[[], None]] = []
        self._since: dict[str, float] = {}  # atom -> when its current value was first seen

    def listen(self, listener: Callable[[], None]) -> None:
        """Call ``listener()`` after every change of the set, refreshes included."""
        self._listeners.append(listener)

    def _changed(self) -> None:
        for listener in self._listeners:
            listener()

    def add(self, obs: Observation) -> bool:
        """``S := S ⊕ o``. True when the set of literals changed (a refresh is no change)."""
        atom = obs.literal.atom
        old = self._by_atom.get(atom)
        if old is not None and old.time > obs.time:
            return False  # a late, older report never overrides a newer one
        self._by_atom[atom] = obs
        changed = old is None or old.literal != obs.literal
        if changed:
            self._since[atom] = obs.time
        self._changed()
        return changed

    def since(self, atom: str) -> float | None:
        """When the atom's current value was first observed (None: unknown)."""
        return self._since.get(atom)

    def retract(self, atom: str) -> bool:
        """Forget what is known about ``atom`` (it becomes unknown). True if it was known."""
        self._since.pop(atom, None)
        known = self._by_atom.pop(atom, None) is not None
        if known:
            self._changed()
        return known

    def expire(self, now: float) -> list[Observation]:
        """Drop and return the observations whose validity ran out at ``now``."""
        gone = [o for o in self._by_atom.values()
                if o.expires_at is not None and o.expires_at <= now]
        for o in gone:
            del self._by_atom[o.literal.atom]
            self._since.pop(o.literal.atom, None)
        if gone:
            self._changed()
        return gone

    def drop_source(self, source: str) -> list[Observation]:
        """Forget everything ``source`` said (an observer that stopped)."""
        gone = [o for o in self._by_atom.values() if o.source == source]
        for o in gone:
            del self._by_atom[o.literal.atom]
            self._since.pop(o.literal.atom, None)
        if gone:
            self._changed()
        return gone

    def next_expiry(self) -> float | None:
        """When the first observation runs out of validity (None: none will)."""
        times = [o.expires_at for o in self._by_atom.values() if o.expires_at is not None]
        return min(times) if times else None

    def get(self, atom: str) -> Observation | None:
        return self._by_atom.get(atom)

    def literals(self) -> list[Literal]:
        return [o.literal for o in self._by_atom.values()]

    def __len__(self) -> int:
        return len(self._by_atom)

    def __contains__(self, literal: object) -> bool:
        if not isinstance(literal, Literal):
            return False
        o = self._by_atom.get(literal.atom)
        return o is not None and o.literal == literal
