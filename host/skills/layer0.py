"""Layer 0 as the layers above see it: a fold of the daemon's event stream.

A skill needs components (``jaguar``, ``hokuyo_node``) and topics (``/scan``). Whether it can run
is decided from what layer 0 *says* — its diagnoses, quarantines, holds and repairs, as events on
the daemon's one stream (``host.events``) — never by reading the board or the processes again.
``Layer0View`` is a reader of that stream (``daemon.subscribe(view)``); it keeps:

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
    ActionState,
    DiagnosisRecord,
    HoldChange,
    Observation,
    QuarantineChange,
    RepairEnded,
    Stamped,
)

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

    def __init__(self, repair_active: Callable[[], bool] | None = None) -> None:
        self.suspects: set[str] = set()
        self.quarantined: dict[str, str] = {}
        self.held: dict[str, str] = {}
        self.repairing: set[str] = set()
        self.bad_topics: set[str] = set()
        self.diagnosed = False
        self._repair_active = repair_active or (lambda: bool(self.repairing))
        self.listeners: list[Callable[[], None]] = []

    def __call__(self, stamped: Stamped) -> None:
        event = stamped.event
        match event:
            case DiagnosisRecord():
                self.suspects = {c for bad in event.diagnoses for c in bad}
                self.diagnosed = True
            case QuarantineChange(quarantined=True):
                self.quarantined[event.component] = event.reason or "quarantined"
            case QuarantineChange():
                self.quarantined.pop(event.component, None)
            case HoldChange(held=True):
                self.held[event.component] = event.reason or f"held by {event.by}"
            case HoldChange():
                self.held.pop(event.component, None)
            case ActionRecord(state=ActionState.STARTED):
                self.repairing |= set(event.args)
            case ActionRecord():
                self.repairing -= set(event.args)
            case RepairEnded():
                self.repairing.clear()
            case Observation() if event.literal.startswith("ok("):
                topic = Atom.parse(event.literal).arg
                if event.value is False:
                    self.bad_topics.add(topic)
                else:
                    self.bad_topics.discard(topic)
            case _:
                return
        for listener in list(self.listeners):
            listener()

    def seed(self, diagnoses: Iterable[Iterable[str]], quarantined: dict[str, str],
             held: dict[str, str]) -> None:
        """Start from what layer 0 says now (a view that subscribes late missed the events)."""
        self.suspects = {c for bad in diagnoses for c in bad}
        self.diagnosed = True
        self.quarantined.update(quarantined)
        self.held.update(held)

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
