"""The mission's steps on a timeline: the layers above the components (paper 001).

``mission_spans(entries, at)`` folds a journal's ``LayerResult`` entries (``host.events``; the
mission's layers journal one per command: 3 a mission action, 2 its behaviour tree, 1 a
skill) into ``LayerSpan``\\ s from the command's start to its end with its outcome, and the
executive's *holds* — a guard's ``TreeChange`` to RUNNING "holding: ..." until that guard next
changes status — into spans of layer 2 marked ``held``, whose ``why`` is every reason the guard
gave as it held, in order ("holding: layer 0: /scan down; then holding: layer 0: hokuyo
repairing"). A command's times are the daemon's clock; they are put on the axis through the
entry that carried them (``at``, the timeline's own placement of an entry, and
``place(value, entry, entry_at)``). The chart (``host.report.chart``) draws them as three
lanes above the repair actions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from host.events import LayerResult, TreeChange
from host.journal.entries import Entry

Place = Callable[[float, Entry, float], float]

LANES = (3, 2, 1)  # top to bottom
LANE_NAMES = {3: "mission actions", 2: "behaviour trees", 1: "skills"}


@dataclass(frozen=True)
class LayerSpan:
    """One command of ``layer`` from ``start`` to ``end`` (seconds on the axis)."""

    layer: int
    label: str
    start: float
    end: float
    ok: bool
    held: bool = False  # a guard holding the tree while layer 0 repairs
    why: str = ""


def mission_spans(entries: Sequence[Entry], at: Callable[[Entry], float], place: Place
                  ) -> list[LayerSpan]:
    spans: list[LayerSpan] = []
    holding: dict[tuple[str, str], tuple[float, str]] = {}
    for e in entries:
        p = e.payload
        if isinstance(p, LayerResult):
            label = f"{p.command}({', '.join(p.args)})"
            why = "" if p.success or not p.explanation else p.explanation[0].what
            t0, t1 = place(p.started, e, at(e)), place(p.finished, e, at(e))
            spans.append(LayerSpan(p.layer, label, t0, max(t0, t1), p.success, why=why))
        elif isinstance(p, TreeChange):
            key = (p.dispatch_id, p.node)
            if p.status == "RUNNING" and p.detail.startswith("holding"):
                t0, why = holding.get(key, (at(e), ""))
                if p.detail not in why.split("; then "):  # the reason changed as it held
                    why = f"{why}; then {p.detail}" if why else p.detail
                holding[key] = (t0, why)
            elif key in holding:
                t0, why = holding.pop(key)
                spans.append(LayerSpan(2, p.node, t0, at(e), True, held=True, why=why))
    for (_, node), (t0, why) in holding.items():  # still holding at the journal's end
        spans.append(LayerSpan(2, node, t0, at(entries[-1]), False, held=True, why=why))
    return sorted(spans, key=lambda s: (s.start, -s.layer))


def clip_spans(spans: Sequence[LayerSpan], ws: float, we: float) -> tuple[LayerSpan, ...]:
    """The spans inside the window [ws, we], shifted so that ``ws`` is 0."""
    out = []
    for s in spans:
        if s.end < ws or s.start > we:
            continue
        out.append(LayerSpan(s.layer, s.label, max(s.start, ws) - ws, min(s.end, we) - ws,
                             s.ok, s.held, s.why))
    return tuple(out)
