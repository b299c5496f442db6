"""Reading a journal back: one-line summaries of entries, and replaying a history into state.

``summarize`` gives the short human line that ``dxboard journal`` prints and the web page shows
in its journal tail. ``Replay`` folds entries, in id order, into what the daemon knew at that
point: the value of every observed literal, the latest diagnoses, and every repair action with
its latest state (the ``started`` entry and the one that finished it share an ``action_id``).
The timeline report and tests use it to check that a journal holds enough to rebuild a history
like the paper's figures 5 and 6 (a row per component, normal or abnormal over time, repair
actions along the top) without the daemon that wrote it.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from dataclasses import dataclass, field

from host.journal.entries import (
    ActionRecord,
    BoardEvent,
    DiagnosisRecord,
    Entry,
    Note,
    Observation,
    Payload,
    PlanRecord,
    Telemetry,
)

log = logging.getLogger(__name__)


def _value(v: bool | None) -> str:
    return "unknown" if v is None else ("true" if v else "false")


def summarize(payload: Payload) -> str:
    """One short line describing a payload, for people."""
    if isinstance(payload, Observation):
        src = f"  [{payload.source}]" if payload.source else ""
        return f"{payload.literal} = {_value(payload.value)}{src}"
    if isinstance(payload, DiagnosisRecord):
        if not payload.diagnoses:
            text = "no diagnosis (observations contradict the model)"
        else:
            text = " | ".join("{" + ", ".join(b) + "}" if b else "{} (all healthy)"
                              for b in payload.diagnoses[:4])
            if len(payload.diagnoses) > 4:
                text += f" | ... ({len(payload.diagnoses)} in all)"
        extra = "" if payload.complete else " (incomplete)"
        trig = f"  [{payload.trigger}]" if payload.trigger else ""
        return f"{text}{extra}{trig}"
    if isinstance(payload, PlanRecord):
        steps = "; ".join(f"{s.action}({', '.join(s.args)})" for s in payload.steps)
        return f"plan {payload.plan_id}: {steps or '(nothing to do)'}"
    if isinstance(payload, ActionRecord):
        took = ("" if payload.finished is None
                else f" after {payload.finished - payload.started:.2f} s")
        detail = f": {payload.detail}" if payload.detail else ""
        return (f"{payload.action}({', '.join(payload.args)}) {payload.state.value}"
                f"{took}{detail}")
    if isinstance(payload, BoardEvent):
        ch = "" if payload.channel is None else f" channel {payload.channel}"
        detail = " ".join(f"{k}={v}" for k, v in payload.detail.items())
        return f"{payload.event}{ch}{'  ' + detail if detail else ''}"
    if isinstance(payload, Telemetry):
        parts = [f"ch{c.channel} {c.mean_ma:.0f} mA" for c in payload.channels]
        return f"{payload.period_s:g} s: " + (", ".join(parts) or "(no readings)")
    if isinstance(payload, Note):
        return payload.text if payload.level == "info" else f"{payload.level}: {payload.text}"
    raise TypeError(f"not a journal payload: {payload!r}")


@dataclass
class Replay:
    """What the daemon knew after the entries folded in so far."""

    observations: dict[str, bool | None] = field(default_factory=dict)
    diagnosis: DiagnosisRecord | None = None
    actions: dict[str, ActionRecord] = field(default_factory=dict)
    plans: list[PlanRecord] = field(default_factory=list)
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
