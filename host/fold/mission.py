"""The mission as every view sees it (paper 001's layers): a fold of the mission's events.

``MissionFold`` reads the mission's events of the daemon's stream (``host.events``) into one
``MissionStatus``: the mission's id and state (started, planned, replanning, completed, stopped,
failed) and why, its goal, the current plan (each step with its planned start and duration) and
the step being carried out, the dispatched action with its behaviour tree's nodes and their
latest status (a guard's reason to hold), the last results of layers 2 and 3 with their
explanations, the recent changes of the knowledge base (effects, sensing, diagnosis), and the
latest plan-execution diagnosis (``diagnosis``: the alarm, the class of the fault, the symptoms,
the fault region, the alternative histories, the winning path of the context tree, the corrected
knowledge base or the plan error, and the new plan the mission made from it). ``EventFold``
(``host.fold.state``) holds it; the page (``host.web.fold``) shows it.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

from host.events import (
    Dispatch,
    Event,
    KbChange,
    LayerResult,
    MissionState,
    PlanDiagnosis,
    TreeChange,
)

RECENT = 12


@dataclass(frozen=True)
class MissionStatus:
    mission_id: str = ""
    state: str = ""
    detail: str = ""
    goal: tuple[str, ...] = ()
    plan: tuple[dict[str, Any], ...] = ()  # {step, start, duration}
    step: int | None = None  # the plan's step being carried out
    action: str = ""  # the dispatched action, e.g. navigate(corridor, office, door_office)
    dispatch_id: str = ""
    tree: tuple[dict[str, str], ...] = ()  # {node, status, detail}
    results: tuple[dict[str, Any], ...] = ()  # the last results of layers 2-3, newest first
    kb: tuple[str, ...] = ()  # recent changes, newest first ("sensing: -(open door_lab)")
    diagnosis: dict[str, Any] = field(default_factory=dict)  # the latest plan diagnosis

    def to_json(self) -> dict[str, Any]:
        return {"mission_id": self.mission_id, "state": self.state, "detail": self.detail,
                "goal": list(self.goal), "plan": list(self.plan), "step": self.step,
                "action": self.action, "dispatch_id": self.dispatch_id,
                "tree": list(self.tree), "results": list(self.results), "kb": list(self.kb),
                "diagnosis": dict(self.diagnosis)}


@dataclass
class MissionFold:
    status: MissionStatus = field(default_factory=MissionStatus)
    _tree: dict[str, dict[str, str]] = field(default_factory=dict)
    _results: deque[dict[str, Any]] = field(default_factory=lambda: deque(maxlen=RECENT))
    _kb: deque[str] = field(default_factory=lambda: deque(maxlen=RECENT))

    def __call__(self, e: Event) -> MissionStatus | None:
        """The new status after ``e``, or None when ``e`` is not the mission's."""
        s = self.status
        match e:
            case MissionState():
                changes: dict[str, Any] = {"mission_id": e.mission_id, "state": e.state,
                                           "detail": e.detail, "goal": e.goal or s.goal}
                if e.state == "planned":
                    changes["plan"] = tuple(
                        {"step": str(p), "start": p.start, "duration": p.duration}
                        for p in e.plan)
                    changes["step"] = None
                    if s.diagnosis and s.diagnosis.get("new_plan") is None:
                        changes["diagnosis"] = {**s.diagnosis, "new_plan": [
                            str(p) for p in e.plan]}  # the plan made from the corrected KB
                s = _replace(s, **changes)
            case PlanDiagnosis():
                diag = e.to_json()
                diag["new_plan"] = None
                s = _replace(s, diagnosis=diag)
            case Dispatch():
                self._tree = {}
                s = _replace(s, step=e.step, action=f"{e.action}({', '.join(e.args)})",
                             dispatch_id=e.dispatch_id, tree=())
            case TreeChange() if e.dispatch_id == s.dispatch_id:
                self._tree[e.node] = {"node": e.node, "status": e.status, "detail": e.detail}
                s = _replace(s, tree=tuple(self._tree.values()))
            case LayerResult() if e.layer >= 2:
                why = "; because ".join(str(c) for c in e.explanation)
                self._results.appendleft({"layer": e.layer, "command": f"{e.command}("
                                          f"{', '.join(e.args)})", "success": e.success,
                                          "why": why})
                s = _replace(s, results=tuple(self._results))
            case KbChange():
                parts = [f"+{a}" for a in e.added] + [f"-{a}" for a in e.removed]
                self._kb.appendleft(f"{e.source}: {' '.join(parts)}"
                                    + (f" ({e.cause})" if e.cause else ""))
                s = _replace(s, kb=tuple(self._kb))
            case _:
                return None
        self.status = s
        return s


def _replace(s: MissionStatus, **changes: Any) -> MissionStatus:
    import dataclasses

    return dataclasses.replace(s, **changes)
