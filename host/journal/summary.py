"""Reading a journal back: one-line summaries of entries, and replaying a history into state.

``summarize`` (``host.events.describe``) gives the short human line that ``dxboard journal``
prints and the web page shows in its journal tail. ``Replay`` folds entries, in id order,
into what the daemon knew at that point: the value of every observed literal, the latest
diagnoses, and every repair action with its latest state (the ``started`` entry and the one
that finished it share an ``action_id``), and what is quarantined or held.
The timeline report and tests use it to check that a journal holds enough to rebuild a history
like the paper's figures 5 and 6 (a row per component, normal or abnormal over time, repair
actions along the top) without the daemon that wrote it.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from dataclasses import dataclass, field

from host.events import (
    ActionRecord,
    DiagnosisRecord,
    HoldChange,
    Observation,
    PlanRecord,
    QuarantineChange,
    describe,
)
from host.journal.entries import Entry

log = logging.getLogger(__name__)


summarize = describe  # the journal's name for it


@dataclass
class Replay:
    """What the daemon knew after the entries folded in so far."""

    observations: dict[str, bool | None] = field(default_factory=dict)
    diagnosis: DiagnosisRecord | None = None
    actions: dict[str, ActionRecord] = field(default_factory=dict)
    plans: list[PlanRecord] = field(default_factory=list)
    quarantined: dict[str, QuarantineChange] = field(default_factory=dict)
    held: dict[str, HoldChange] = field(default_factory=dict)
    last_id: int = 0
    last_wall: float = 0.0

    def apply(self, entry: Entry) -> None:
        """Fold one entry in; entries must come in id order."""
        if entry.id <= self.last_id:
            raise ValueError(f"entry {entry.id} replayed after {self.last_id}")
        self.last_id, self.last_wall = entry.id, entry.wall
        p = entry.payload
        if isinstance(p, Observation):
            self.observations[p.literal] = p.value
        elif isinstance(p, DiagnosisRecord):
            self.diagnosis = p
        elif isinstance(p, ActionRecord):
            self.actions[p.action_id] = p
        elif isinstance(p, PlanRecord):
            self.plans.append(p)
        elif isinstance(p, QuarantineChange):
            if p.quarantined:
                self.quarantined[p.component] = p
            else:
                self.quarantined.pop(p.component, None)
        elif isinstance(p, HoldChange):
            if p.held:
                self.held[p.component] = p
            else:
                self.held.pop(p.component, None)

    @classmethod
    def of(cls, entries: Iterable[Entry]) -> Replay:
        replay = cls()
        for entry in entries:
            replay.apply(entry)
        return replay

    def abnormal(self) -> frozenset[str]:
        """Components in every current diagnosis (surely broken), as the timeline rows show."""
        if self.diagnosis is None or not self.diagnosis.diagnoses:
            return frozenset()
        sets = [frozenset(b) for b in self.diagnosis.diagnoses]
        return frozenset.intersection(*sets)
