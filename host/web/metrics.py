"""Prometheus metrics for ``GET /metrics``, in the text exposition format (version 0.0.4).

Written by hand rather than with ``prometheus_client``: every value is already a field of the
daemon's ``Status`` snapshot or a journal count, so all that is needed is the format itself —
``# HELP`` and ``# TYPE`` lines, then ``name{label="value"} number`` samples, label values
escaped (backslash, double quote, newline) — about forty lines, against a dependency with a
process-global registry that would have to be kept in sync with the snapshot. Exported: each
channel's current, on flag and state (one series per state, 1 for the current one, the usual
"enum" pattern); observed literals by value; observation changes, diagnosis runs and their
latency (a summary's ``_sum`` and ``_count``, plus the last run's latency); repairs by outcome;
a gauge per component out of automatic repair (``dxboard_component_quarantined`` and
``dxboard_component_held``, 1 while it is; its series ends when a person releases it, so an
alert is ``dxboard_component_quarantined == 1``); the journal's size and entries by kind;
whether the board link is up. A fleet's Prometheus
scrapes these directly (ARCHITECTURE.md, "Fleets").
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Mapping

from host.web.status import CHANNEL_STATES, Status

log = logging.getLogger(__name__)

CONTENT_TYPE = "text/plain; version=0.0.4; charset=utf-8"

Sample = tuple[Mapping[str, str], float]


def _escape(value: str) -> str:
    return value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")


def _number(value: float) -> str:
    if math.isnan(value):
        return "NaN"
    if math.isinf(value):
        return "+Inf" if value > 0 else "-Inf"
    return repr(float(value)) if not float(value).is_integer() else str(int(value))


def family(name: str, kind: str, help_text: str, samples: Iterable[Sample],
           suffix_samples: Iterable[tuple[str, Sample]] = ()) -> list[str]:
    """The lines of one metric family: HELP, TYPE, then its samples."""
    lines = [f"# HELP {name} {help_text}", f"# TYPE {name} {kind}"]
    all_samples = [("", s) for s in samples] + list(suffix_samples)
    for suffix, (labels, value) in all_samples:
        text = ",".join(f'{k}="{_escape(v)}"' for k, v in labels.items())
        lines.append(f"{name}{suffix}{{{text}}} {_number(value)}" if text
                     else f"{name}{suffix} {_number(value)}")
    return lines


def render(status: Status, journal_counts: Mapping[str, int] | None = None,
           journal_bytes: int | None = None) -> str:
    """The whole exposition for one snapshot (and the journal's counts, if there is one)."""
    ch = [({"channel": str(c.id), "name": c.name}, c) for c in status.channels]
    lines: list[str] = []
    lines += family("dxboard_board_link_up", "gauge", "1 if the link to the board is up.",
                    [({}, 1.0 if status.board_link_up else 0.0)])
    lines += family("dxboard_channel_current_milliamperes", "gauge",
                    "Last measured current of each board channel.",
                    [(labels, c.current_ma) for labels, c in ch])
    lines += family("dxboard_channel_on", "gauge", "1 if the channel is switched on.",
                    [(labels, 1.0 if c.on else 0.0) for labels, c in ch])
    states = list(CHANNEL_STATES) + sorted({c.state for _, c in ch} - set(CHANNEL_STATES))
    lines += family("dxboard_channel_state", "gauge",
                    "1 for the channel's current state, 0 for the others.",
                    [({**labels, "state": s}, 1.0 if c.state == s else 0.0)
                     for labels, c in ch for s in states])
    values = {"true": 0, "false": 0, "unknown": 0}
    for v in status.observations.values():
        values["unknown" if v is None else ("true" if v else "false")] += 1
    lines += family("dxboard_observations", "gauge", "Observed literals by their current value.",
                    [({"value": k}, float(n)) for k, n in values.items()])
    lines += family("dxboard_observation_changes_total", "counter",
                    "Changes of observed literals since the daemon started.",
                    [({}, float(status.observation_changes))])
    lines += family("dxboard_diagnoses", "gauge", "Minimal diagnoses currently held.",
                    [({}, float(len(status.diagnoses)))])
    lines += family("dxboard_diagnosis_duration_seconds", "summary",
                    "Time the diagnoser took per run.", [],
                    [("_sum", ({}, status.diagnosis_latency_sum_s)),
                     ("_count", ({}, float(status.diagnosis_runs)))])
    if status.diagnosis_last_latency_s is not None:
        lines += family("dxboard_diagnosis_last_duration_seconds", "gauge",
                        "Time the latest diagnoser run took.",
                        [({}, status.diagnosis_last_latency_s)])
    outcomes = {"succeeded": 0, "failed": 0, "timeout": 0, **status.repairs_by_outcome}
    lines += family("dxboard_repairs_total", "counter", "Repair actions finished, by outcome.",
                    [({"outcome": k}, float(n)) for k, n in sorted(outcomes.items())])
    lines += family("dxboard_component_quarantined", "gauge",
                    "1 for each component quarantined: out of automatic repair until a person "
                    "clears it (dxboard quarantine clear).",
                    [({"component": c}, 1.0) for c in sorted(status.quarantined)])
    lines += family("dxboard_component_held", "gauge",
                    "1 for each component held: no repair touches it until a person releases "
                    "it (dxboard hold release).",
                    [({"component": c}, 1.0) for c in sorted(status.held)])
    if journal_bytes is not None:
        lines += family("dxboard_journal_bytes", "gauge",
                        "Size of the journal file and its write-ahead log.",
                        [({}, float(journal_bytes))])
    if journal_counts is not None:
        lines += family("dxboard_journal_entries", "gauge", "Journal entries by kind.",
                        [({"kind": k}, float(n)) for k, n in sorted(journal_counts.items())])
    return "\n".join(lines) + "\n"
