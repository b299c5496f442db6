"""Layer 0 as the layers above see it: a projection of the one fold of the daemon's event stream.

A skill needs components (``jaguar``, ``hokuyo_node``) and topics (``/scan``). Whether it can run
is decided from what layer 0 *says* — its diagnoses, quarantines, holds and repairs, as events on
the daemon's one stream (``host.events``) — never by reading the board or the processes again.
``Layer0View`` is a reader of that stream (``daemon.subscribe(view)``) that feeds an
``EventFold`` (``host.fold``, the fold the page and ``/diagnostics`` read; one that is given
the daemon's fold only reads it) and reads from it:

- ``suspects``: the components in any minimal diagnosis of the latest ``DiagnosisRecord``;
- ``quarantined`` and ``held`` (``QuarantineChange``, ``HoldChange``), with their reasons;
- ``repairing``: the components a repair action is working on now (an ``ActionRecord`` from
  its start to its end; all cleared by ``RepairEnded``) — not every component of the plan, so
  that a skill goes on as soon as what it needs is diagnosed normal and left alone, while the
  repair carries on elsewhere;
- ``bad_topics``: topics observed not ``ok`` (``Observation`` of ``ok(/t)`` false).

``availability(needs)`` is the skills' and guards' question: ``ok``; ``hold`` while layer 0 is
working on a needed component (diagnosed abnormal, being repaired, or a needed topic is down
while a repair may still bring it back) — not a failure yet; or ``unavailable`` when a needed
component is quarantined or held by a person, which no waiting cures: the planner must plan
around it or the mission stop, naming it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from enum import StrEnum

from host.atoms import Atom
from host.events import (
    ActionRecord,
    DiagnosisRecord,
    Event,
    HoldChange,
    Observation,
    QuarantineChange,
    RepairEnded,
    Stamped,
)
from host.fold import EventFold

log = logging.getLogger(__name__)


class AvailState(StrEnum):
    OK = "ok"
    HOLD = "hold"
    UNAVAILABLE = "unavailable"


@dataclass(frozen=True)
class Availability:
    state: AvailState
    components: tuple[str, ...] = ()
    why: str = ""

    @property
    def ok(self) -> bool:
        return self.state is AvailState.OK


class Layer0View:
    """What layer 0 has said so far; call it with every stamped event of the stream."""

    def __init__(self, repair_active: Callable[[], bool] | None = None,
                 fold: EventFold | None = None) -> None:
        self._own_fold = fold is None  # then this view feeds it
        self.fold = fold if fold is not None else EventFold()
        self._repair_active = repair_active or (lambda: bool(self.repairing))
        self.listeners: list[Callable[[], None]] = []
        self.fold.listeners.append(self._changed)

    def __call__(self, stamped: Stamped) -> None:
        if self._own_fold:
            self.fold.feed(stamped)

    def detach(self) -> None:
        """Stop listening to the fold (a view on the daemon's own fold, when its mission ends)."""
        if self._changed in self.fold.listeners:
            self.fold.listeners.remove(self._changed)

    def _changed(self, stamped: Stamped) -> None:
        """The fold changed: tell the listeners when it was something layer 0 says."""
        e = stamped.event
        if isinstance(e, DiagnosisRecord | QuarantineChange | HoldChange | ActionRecord
                      | RepairEnded) or (isinstance(e, Observation)
                                         and e.literal.startswith("ok(")):
            for listener in list(self.listeners):
                listener()

    @property
    def diagnosed(self) -> bool:
        return self.fold.diagnosis is not None

    @property
    def suspects(self) -> set[str]:
        return self.fold.suspects

    @property
    def quarantined(self) -> dict[str, str]:
        return {c: why or "quarantined" for c, why in self.fold.quarantined.items()}

    @property
    def held(self) -> dict[str, str]:
        return {x.component: x.reason or f"held by {x.by}"
                for x in self.fold.out_of_repair("held")}

    @property
    def repairing(self) -> set[str]:
        return self.fold.repairing

    @property
    def bad_topics(self) -> set[str]:
        """Topics observed not ``ok`` (``ok(/t)`` false)."""
        return {Atom.parse(lit).arg for lit, value in self.fold.observations.items()
                if lit.startswith("ok(") and value is False}

    def seed(self, diagnoses: Iterable[Iterable[str]], quarantined: dict[str, str],
             held: dict[str, str]) -> None:
        """Start from what layer 0 says now (a view that subscribes late missed the events;
        one reading the daemon's own fold missed nothing)."""
        if not self._own_fold:
            return
        told: list[Event] = [DiagnosisRecord.of([list(bad) for bad in diagnoses]),
                *(QuarantineChange(c, True, why) for c, why in quarantined.items()),
                *(HoldChange(c, True, why) for c, why in held.items())]
        for event in told:
            self.fold.feed(Stamped(0.0, 0.0, event))

    def availability(self, needs: Iterable[str]) -> Availability:
        needs = list(needs)
        comps = [n for n in needs if not n.startswith("/")]
        topics = [n for n in needs if n.startswith("/")]
        out = sorted(c for c in comps if c in self.quarantined)
        if out:
            return Availability(AvailState.UNAVAILABLE, tuple(out), "; ".join(
                f"{c} is quarantined ({self.quarantined[c]})" for c in out))
        held = sorted(c for c in comps if c in self.held)
        if held:
            return Availability(AvailState.UNAVAILABLE, tuple(held), "; ".join(
                f"{c} is held ({self.held[c]})" for c in held))
        sick = sorted(c for c in comps if c in self.suspects or c in self.repairing)
        down = sorted(t for t in topics if t in self.bad_topics)
        if sick:
            doing = "repairing" if self._repair_active() else "diagnosed abnormal"
            return Availability(AvailState.HOLD, tuple(sick),
                                f"layer 0: {', '.join(sick)} {doing}"
                                + (f" ({', '.join(down)} down)" if down else ""))
        if down:
            blame = sorted(self.suspects)
            return Availability(AvailState.HOLD, tuple(blame),
                                f"layer 0: {', '.join(down)} down"
                                + (f", diagnosed {', '.join(blame)}" if blame else ""))
        return Availability(AvailState.OK)

    def explain(self, needs: Iterable[str]) -> tuple[str, ...]:
        """The needed components layer 0 blames now (diagnosed, quarantined or held)."""
        return tuple(sorted(c for c in needs if c in self.suspects or c in self.quarantined
                            or c in self.held))
