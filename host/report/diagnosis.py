"""The mission's plan-execution diagnoses on a timeline (issue 16, papers 001 and 004).

``diagnosis_marks(entries, at)`` turns each ``PlanDiagnosis`` journal entry (``host.events``,
kind ``plan_diagnosis``: what the mission layer journals when a step's alarm is explained) into
a ``DiagnosisMark`` at the entry's place on the axis (``at``, the timeline's own placement),
with the step it explained, the class of the fault (exogenous event, action fault, plan error,
component fault; several when the most probable history mixes them; none when nothing explains
the alarm) and a short explanation for the chart: the most probable alternative history without
its rank and probability ("door-closes(door_office) before step 7"), or for a plan error the
action that could not have worked and the condition the domain may lack. ``clip_marks`` keeps
those inside a window. The chart (``host.report.chart``) draws them in the mission band.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from host.events import PlanDiagnosis
from host.journal.entries import Entry

log = logging.getLogger(__name__)

#: the classes of fault a plan-execution diagnosis names (``host.plandiag.result.FaultClass``)
CLASSES = ("exogenous event", "action fault", "plan error", "component fault")
UNEXPLAINED = "unexplained"  # the class shown when no history explains the alarm

_RANK = re.compile(r"^\s*\d+\.\s+p=[0-9.eE+-]+\s+")  # "1. p=1.000  " before a history
_EACH = re.compile(r", p=[0-9.eE+-]+ each$")  # a group of one-event histories
_PLAN_ERROR = re.compile(r"^plan error at step (\d+) (.+?): ")
_LACKS = "; the domain may lack "


@dataclass(frozen=True)
class DiagnosisMark:
    """One plan-execution diagnosis at ``time`` (seconds on the axis)."""

    time: float
    step: int
    dispatch_id: str
    classes: tuple[str, ...]
    text: str  # the short explanation

    @property
    def cls(self) -> str:
        """The class the chart colours the mark by: the first named, else ``unexplained``."""
        return self.classes[0] if self.classes else UNEXPLAINED

    @property
    def label(self) -> str:
        """The text beside the mark: its class(es) and the short explanation."""
        return f"{' + '.join(self.classes) or UNEXPLAINED}: {self.text}"


def short_explanation(p: PlanDiagnosis) -> str:
    """The most probable history in a few words, or the plan error, or why nothing is."""
    if p.histories:
        text = _EACH.sub("", _RANK.sub("", p.histories[0]))
        if len(p.classes) <= 1:  # the class is shown apart: drop it from each fault
            text = "; ".join(_drop_class(part) for part in text.split("; "))
        return text
    if p.plan_error:
        m = _PLAN_ERROR.match(p.plan_error)
        head = f"{m.group(2)} at step {m.group(1)}" if m else f"step {p.step}"
        if _LACKS in p.plan_error:
            lacks = p.plan_error.split(_LACKS, 1)[1].split(_LACKS)[0].rsplit(" (", 1)[0]
            return f"{head}: the domain may lack {lacks}"
        return f"{head} could not have worked"
    return f"nothing explains the alarm at step {p.step}"


def _drop_class(fault: str) -> str:
    for c in CLASSES:
        if fault.startswith(f"{c}: "):
            return fault[len(c) + 2:]
    return fault


def diagnosis_marks(entries: Sequence[Entry], at: Callable[[Entry], float]
                    ) -> list[DiagnosisMark]:
    marks = []
    for e in entries:
        p = e.payload
        if isinstance(p, PlanDiagnosis):
            marks.append(DiagnosisMark(at(e), p.step, p.dispatch_id, tuple(p.classes),
                                       short_explanation(p)))
    return marks


def clip_marks(marks: Sequence[DiagnosisMark], ws: float, we: float
               ) -> tuple[DiagnosisMark, ...]:
    """The marks inside the window [ws, we], shifted so that ``ws`` is 0."""
    return tuple(DiagnosisMark(m.time - ws, m.step, m.dispatch_id, m.classes, m.text)
                 for m in marks if ws <= m.time <= we)
