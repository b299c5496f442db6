"""Reading a journal back: one-line summaries of entries, and replaying a history into state.

``summarize`` (``host.events.describe``) gives the short human line that ``dxboard journal``
prints and the web page shows in its journal tail. ``Replay`` folds entries, in id order, with
the one fold of the event stream (``host.fold.EventFold``, which the live views read too),
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

from host.events import (
    ActionRecord,
    DiagnosisRecord,
    HoldChange,
    PlanRecord,
    QuarantineChange,
    Stamped,
    describe,
)
from host.fold import EventFold
from host.journal.entries import Entry

log = logging.getLogger(__name__)


summarize = describe  # the journal's name for it


class Replay:
    """What the daemon knew after the entries folded in so far (by the one ``EventFold``,
    keeping every action and plan: a journal is read once, offline)."""

    def __init__(self) -> None:
        self.fold = EventFold(keep_actions=None, keep_plans=None)
        self.last_id = 0
        self.last_wall = 0.0

    def apply(self, entry: Entry) -> None:
        """Fold one entry in; entries must come in id order."""
        if entry.id <= self.last_id:
            raise ValueError(f"entry {entry.id} replayed after {self.last_id}")
        self.last_id, self.last_wall = entry.id, entry.wall
        self.fold.feed(Stamped(entry.wall, entry.mono, entry.payload))

    @classmethod
    def of(cls, entries: Iterable[Entry]) -> Replay:
        replay = cls()
        for entry in entries:
            replay.apply(entry)
        return replay

    @property
    def observations(self) -> dict[str, bool | None]:
        return self.fold.observations

    @property
    def diagnosis(self) -> DiagnosisRecord | None:
        return self.fold.diagnosis

    @property
    def actions(self) -> dict[str, ActionRecord]:
        """Every repair action by id, with its latest state, in the order they started."""
        return {aid: a.record for aid, a in self.fold.actions.items()}

    @property
    def plans(self) -> list[PlanRecord]:
        return list(self.fold.plans)

    @property
    def quarantined(self) -> dict[str, QuarantineChange]:
        return {x.component: x.change for x in self.fold.out_of_repair("quarantined")
                if isinstance(x.change, QuarantineChange)}

    @property
    def held(self) -> dict[str, HoldChange]:
        return {x.component: x.change for x in self.fold.out_of_repair("held")
                if isinstance(x.change, HoldChange)}

    def abnormal(self) -> frozenset[str]:
        """Components in every current diagnosis (surely broken), as the timeline rows show."""
        if self.diagnosis is None or not self.diagnosis.diagnoses:
            return frozenset()
        sets = [frozenset(b) for b in self.diagnosis.diagnoses]
        return frozenset.intersection(*sets)
