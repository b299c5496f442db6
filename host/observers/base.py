"""The observer base: one input, literals out, emitted on change plus a periodic refresh.

An observer (paper 000 §IV-B) watches one aspect of the robot and reports it as literals for
the diagnoser's observation set (``host.diagnosis.observations``). Each ``Observer`` here is a
small state machine with one typed input and no I/O: the daemon (or ``ObserverHub``) hands it
an input with ``feed(item, now)`` and calls ``tick(now)`` no later than ``next_deadline()``;
both return the ``Update`` values to apply — an ``Observation`` (``S ⊕ o``) or a ``Retraction``
(the atom becomes *unknown*: unknown is not false). Time is always passed in; nothing here
reads a clock, so tests can run on a simulated one.

Emission rules, shared by every kind:

- a literal is emitted at once when its value changes (event-driven, not a 1 s poll);
- an unchanged literal is re-emitted every ``refresh`` seconds with the current time, and every
  observation carries ``validity`` (> ``refresh``), so an observer that falls silent (a dead
  input, a stopped task) lets its literals expire to unknown in the diagnoser;
- an observer that loses its evidence (a board link down, a window with too few samples)
  retracts its literals at once rather than waiting for expiry — no diagnosis on stale data.

``next_deadline()`` is the earliest time at which a ``tick`` could change or refresh something
(a silence limit, a response deadline, a refresh): the hub sleeps exactly until then, so
time-based rules fire at their deadline, not at the next poll.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Generic, Protocol, TypeVar

from host.diagnosis.logic import Literal
from host.diagnosis.observations import Observation

DEFAULT_REFRESH = 1.0
DEFAULT_VALIDITY = 3.0


@dataclass(frozen=True)
class Retraction:
    """What ``source`` said about ``atom`` no longer holds: the atom is unknown from ``time``."""

    atom: str
    time: float
    source: str


Update = Observation | Retraction


class ObservationSink(Protocol):
    """What updates are applied to: a ``Diagnoser`` (or an ``ObservationSet`` wrapper)."""

    def observe(self, obs: Observation) -> bool: ...

    def retract(self, atom: str) -> bool: ...


def apply_updates(updates: Iterable[Update], sink: ObservationSink) -> bool:
    """Apply ``updates`` in order to ``sink``; True if its literal set changed."""
    changed = False
    for u in updates:
        if isinstance(u, Observation):
            changed = sink.observe(u) or changed
        else:
            changed = sink.retract(u.atom) or changed
    return changed


In = TypeVar("In")


class Observer(ABC, Generic[In]):
    """One observer: ``feed`` its input, ``tick`` it by ``next_deadline``; both return updates.

    Subclasses implement ``_feed`` (and ``_check``/``_deadline`` for time-based rules) and
    call ``_say(atom, positive, now)`` / ``_forget(atom, now)``; the base does the change
    detection, the refresh and the bookkeeping of what is currently asserted.
    """

    kind: str = "observer"
    #: True for observers whose literals rest on inputs alone (a node's process samples, a
    #: topic's values): with no input for ``validity`` seconds they retract everything rather
    #: than refresh stale literals. Observers for which silence is itself evidence (topic
    #: frequency, responses) and the hardware observer (its own link rule) set False.
    needs_input: bool = True

    def __init__(self, name: str, validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH) -> None:
        if not 0 < refresh < validity:
            raise ValueError(f"{name}: need 0 < refresh ({refresh}) < validity ({validity})")
        self.name = name
        self.validity = validity
        self.refresh = refresh
        self._said: dict[str, tuple[bool, float]] = {}  # atom -> (positive, last emitted at)
        self._refresh_due: float | None = None  # the earliest refresh (kept while unchanged)
        self._refresh_known = True  # False: ``_said`` changed since it was computed
        self._fed_at: float | None = None
        self._out: list[Update] = []

    # -- the public half -------------------------------------------------------------------
    def feed(self, item: In, now: float) -> list[Update]:
        """Take one input observed at ``now``; return the updates it causes."""
        self._fed_at = now
        self._feed(item, now)
        return self._flush()

    def tick(self, now: float, read: float | None = None) -> list[Update]:
        """Apply the time-based rules and refreshes due at ``now``. ``read``: the time up to
        which the inputs have been read, when that is earlier (a daemon behind its messages,
        ``host.observers.hub``): the rules judge there, never ahead of an input still waiting
        to be read; the refreshes go out at ``now`` all the same (the observer is alive)."""
        at = now if read is None else min(now, read)
        if self._starved(at):
            for atom in list(self._said):
                self._forget(atom, at)
        self._check(at)
        for atom, (positive, last) in list(self._said.items()):
            if now >= last + self.refresh:
                self._emit(atom, positive, now)
        return self._flush()

    def next_deadline(self) -> float | None:
        """The earliest time a ``tick`` is needed (None: only inputs can change anything)."""
        if not self._refresh_known:  # (called after every input: kept while unchanged)
            self._refresh_due = min((last for _, last in self._said.values()),
                                    default=None)
            self._refresh_known = True
        due = None if self._refresh_due is None else self._refresh_due + self.refresh
        own = self._deadline()
        if own is not None and (due is None or own < due):
            due = own
        if self.needs_input and self._fed_at is not None and self._said:
            starve = self._fed_at + self.validity
            if due is None or starve < due:
                due = starve
        return due

    def stop(self, now: float) -> list[Update]:
        """Retract everything this observer asserted (it is being shut down)."""
        for atom in list(self._said):
            self._forget(atom, now)
        return self._flush()

    @property
    def asserted(self) -> dict[str, bool]:
        """The atoms this observer currently asserts, with their sign."""
        return {a: p for a, (p, _) in self._said.items()}

    @abstractmethod
    def atoms(self) -> list[str]:
        """Every atom this observer can emit (to check against the diagnosis model)."""

    def judge_s(self) -> dict[str, float]:
        """How long after its cause is there this observer needs to say each atom it judges
        slowly (a repair step waits that much longer for it). The default: none."""
        return {}

    def confirmed(self, atom: str) -> bool:
        """Is what this observer asserts of ``atom`` now an abnormal finding it confirmed
        before saying it (a silence in the publisher's own time, a trip the board's readings
        bore out), so that a repair need not wait to see it hold? The default: no."""
        return False

    # -- the private half ------------------------------------------------------------------
    @abstractmethod
    def _feed(self, item: In, now: float) -> None: ...

    def _check(self, now: float) -> None:
        """Time-based rules (silence, deadlines); the default has none."""

    def _deadline(self) -> float | None:
        return None

    def _starved(self, now: float) -> bool:
        return (self.needs_input and self._fed_at is not None
                and now >= self._fed_at + self.validity)

    def _say(self, atom: str, positive: bool, now: float) -> None:
        old = self._said.get(atom)
        if old is None or old[0] != positive:
            self._emit(atom, positive, now)

    def _forget(self, atom: str, now: float) -> None:
        if self._said.pop(atom, None) is not None:
            self._refresh_known = False
            self._out.append(Retraction(atom, now, self.name))

    def _emit(self, atom: str, positive: bool, now: float) -> None:
        self._said[atom] = (positive, now)
        self._refresh_known = False
        self._out.append(Observation(Literal(atom, positive), now, self.name, self.validity))

    def _flush(self) -> list[Update]:
        out, self._out = self._out, []
        return out
