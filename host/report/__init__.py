"""The timeline report: a journal's repair history drawn like paper 000's figures 5 and 6.

``timeline`` folds journal entries into a ``Timeline`` (per component: normal, abnormal and
unknown intervals from the diagnoses; the repair actions with start, end and outcome; the
plans; the moments the whole system became normal again; a mission's layers and its
plan-execution diagnoses), pure and without matplotlib;
``source`` reads a journal file, an optional robot model and a window into one; ``chart``
draws it with matplotlib (Agg) into a PNG or an SVG. ``dxboard report`` is the command.
"""

from host.report.diagnosis import DiagnosisMark
from host.report.timeline import (
    ActionSpan,
    ComponentRow,
    Group,
    HealthState,
    Interval,
    PlanMark,
    Recovery,
    Timeline,
    WindowBound,
    build_timeline,
)

__all__ = [
    "ActionSpan",
    "ComponentRow",
    "DiagnosisMark",
    "Group",
    "HealthState",
    "Interval",
    "PlanMark",
    "Recovery",
    "Timeline",
    "WindowBound",
    "build_timeline",
]
