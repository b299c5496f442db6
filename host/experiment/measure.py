"""What the journal says an experiment did: diagnoses, plans, actions and their times.

Times are seconds since an origin on the daemon's monotonic clock (the journal's ``mono``):
the daemon's start for the power-up, the moment the operator switched the device off for the
device shut-down. ``all_normal_s`` is when the robot became all-normal *and stayed so*: the
first all-normal diagnosis after the last abnormal one (the nodes' observers may briefly
report a gap while a plan is still running; that does not count as done).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from host.journal import ActionRecord, DiagnosisRecord, Entry, Observation, PlanRecord


@dataclass(frozen=True)
class ActionTime:
    action: str
    args: tuple[str, ...]
    state: str
    start_s: float
    end_s: float | None
    plan_id: str = ""
    detail: str = ""

    def __str__(self) -> str:
        return f"{self.action}({', '.join(self.args)})"

    def to_json(self) -> dict[str, Any]:
        return {"action": self.action, "args": list(self.args), "state": self.state,
                "start_s": _r(self.start_s), "end_s": _r(self.end_s), "plan_id": self.plan_id}


@dataclass
class RunResult:
    """One run of an experiment, as measured from its journal."""

    label: str
    first_diagnosis: list[str] = field(default_factory=list)  # first-ranked bad set
    diagnosis_s: float | None = None
    plans: list[tuple[str, float, list[str]]] = field(default_factory=list)  # id, time, steps
    actions: list[ActionTime] = field(default_factory=list)
    detected_s: float | None = None  # first observation change after the origin
    all_normal_s: float | None = None  # the first all-normal diagnosis that lasted
    repair_done_s: float | None = None  # the last action's end (its effect verified)
    first_action_s: float | None = None
    origin_wall: float = 0.0
    journal: str = ""
    journal_from: int | None = None  # the run's first journal id, when the journal holds more

    @property
    def plan(self) -> list[str]:
        """Every step planned, in order (a run may plan more than once, as the paper's §VI-B)."""
        return [s for _, _, steps in self.plans for s in steps]

    @property
    def repair_s(self) -> float | None:
        """From the first repair action's start to all-normal (the paper's 8.1 s -> 38.3 s)."""
        if self.all_normal_s is None or self.first_action_s is None:
            return None
        return self.all_normal_s - self.first_action_s

    def to_json(self) -> dict[str, Any]:
        return {
            "first_diagnosis": self.first_diagnosis,
            "diagnosis_s": _r(self.diagnosis_s),
            "detected_s": _r(self.detected_s),
            "plan": self.plan,
            "plans": [{"plan_id": p, "at_s": _r(t), "steps": s} for p, t, s in self.plans],
            "actions": [a.to_json() for a in self.actions],
            "first_action_s": _r(self.first_action_s),
            "time_to_healthy_s": _r(self.all_normal_s),
            "repair_done_s": _r(self.repair_done_s),
            "repair_s": _r(self.repair_s),
            "journal": self.journal,
            "journal_from": self.journal_from,
        }


def _r(x: float | None) -> float | None:
    return None if x is None else round(x, 2)


def normal(rec: DiagnosisRecord) -> bool:
    """A diagnosis saying nothing is broken."""
    return all(not d for d in rec.diagnoses)


def measure(entries: list[Entry], origin: float, label: str,
            first_is_plan_basis: bool = True) -> RunResult:
    """The run in ``entries`` (every entry from the origin on), times since ``origin``."""
    res = RunResult(label)
    diags = [(e.mono - origin, e.payload) for e in entries
             if isinstance(e.payload, DiagnosisRecord)]
    plans = [(e.mono - origin, e.payload) for e in entries if isinstance(e.payload, PlanRecord)]
    res.plans = [(p.plan_id, t, [f"{s.action}({', '.join(s.args)})" for s in p.steps])
                 for t, p in plans]
    for e in entries:
        if isinstance(e.payload, Observation):
            res.detected_s = e.mono - origin
            res.origin_wall = e.wall - res.detected_s
            break
    # the diagnosis the first plan was made on (else the first abnormal one)
    basis: tuple[float, DiagnosisRecord] | None = None
    for t, d in diags:
        if normal(d):
            continue
        if first_is_plan_basis and plans and t > plans[0][0]:
            break
        basis = (t, d)
        if not first_is_plan_basis or not plans:
            break
    if basis is not None:
        res.diagnosis_s = basis[0]
        res.first_diagnosis = sorted(basis[1].diagnoses[0])
    # each action's last state
    last: dict[str, ActionTime] = {}
    for e in entries:
        a = e.payload
        if isinstance(a, ActionRecord) and not a.plan_id.startswith("quarantine"):
            last[a.action_id] = ActionTime(
                a.action, tuple(a.args), str(a.state), a.started - origin,
                None if a.finished is None else a.finished - origin, a.plan_id, a.detail)
    res.actions = sorted(last.values(), key=lambda a: a.start_s)
    if res.actions:
        res.first_action_s = res.actions[0].start_s
    abnormal_seen = [i for i, (_, d) in enumerate(diags) if not normal(d)]
    if abnormal_seen:
        after = [t for t, d in diags[abnormal_seen[-1] + 1:] if normal(d)]
        res.all_normal_s = after[0] if after else None
    ends = [a.end_s for a in res.actions]
    if ends and None not in ends:
        res.repair_done_s = max(e for e in ends if e is not None)
    return res
